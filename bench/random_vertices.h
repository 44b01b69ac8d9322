// Random vertices of a mesh, set up to trace from as shadowed_transfer does: the vertex's normal
// and tangent frame, and its ray origin pushed off the surface in the scene's local frame. Shared
// by bench/'s estimator prototypes (adaptive_lattice.cpp, horizon_cv.cpp).
#pragma once

#include <vector>

#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/transfer.h"
#include "prtsub/subdiv/random.h"

namespace prtsub {

struct BenchVertex {
  Eigen::Vector3d n, t, b;
  Eigen::Vector3f origin;
};

//! `count` vertices drawn with replacement (seed 3: the same ones in every program).
inline std::vector<BenchVertex> random_vertices(const Mesh& mesh, const RayScene& scene, int count) {
  const RowMatrixX3d offsets = vertex_offset_directions(mesh), points = vertex_positions(mesh);
  Rng pick(3, 0);
  std::vector<BenchVertex> out;
  for (int i = 0; i < count; ++i) {
    const auto id = Eigen::Index(pick.next() % uint64_t(mesh.num_vertices()));
    BenchVertex v;
    v.n = mesh.normals.row(id).transpose();
    tangent_frame(v.n, v.t, v.b);
    const Eigen::Vector3f local = scene.to_local(points.row(id).transpose());
    v.origin = local + scene.ray_offset(local) * Eigen::Vector3d(offsets.row(id).transpose()).cast<float>();
    out.push_back(v);
  }
  return out;
}

}  // namespace prtsub
