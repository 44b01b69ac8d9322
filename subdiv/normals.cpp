// Crease-aware vertex normals.
//
// Every corner starts in its own group. For each manifold edge (exactly two faces, opposite
// traversal) whose two face normals are within the crease angle, the corners of the two faces
// at each end of the edge are united (union-find). A group is then a fan of faces around one
// position connected through smooth edges, so a position gets one normal per crease side and
// faces that only touch at a vertex (bow-ties) never share one. The group's normal is the
// angle-weighted sum of its faces' normals (Thürmer and Wüthrich), which does not depend on
// how a polygon was triangulated.
#include "prtsub/subdiv/normals.h"

#include "prtsub/subdiv/adjacency.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace prtsub {
namespace {

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Groups made only of zero-area faces (their normal is NaN here) take the area-weighted normal
// of every face at their position, ignoring creases; failing that, +z.
void fill_degenerate_groups(const RowMatrixX3d& positions, const std::vector<Triangle>& triangles, CornerNormals& out) {
  bool need_fallback = false;
  for (Eigen::Index g = 0; g < out.normals.rows(); ++g) need_fallback |= std::isnan(out.normals(g, 0));
  if (!need_fallback) return;
  std::vector<Eigen::Vector3d> at_position(static_cast<size_t>(positions.rows()), Eigen::Vector3d::Zero());
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Eigen::Vector3d p0 = positions.row(triangles[f][0]).transpose();
    const Eigen::Vector3d n = (Eigen::Vector3d(positions.row(triangles[f][1]).transpose()) - p0)
                                  .cross(Eigen::Vector3d(positions.row(triangles[f][2]).transpose()) - p0);
    if (!n.allFinite()) continue;
    for (int k = 0; k < 3; ++k) at_position[triangles[f][k]] += n;
  }
  for (uint32_t c = 0; c < triangles.size() * 3; ++c) {
    const Eigen::Index g = out.group[c];
    if (!std::isnan(out.normals(g, 0))) continue;
    const Eigen::Vector3d n = at_position[triangles[c / 3][c % 3]];
    const double len = n.norm();
    if (len > 1e-300 && std::isfinite(len)) out.normals.row(g) = (n / len).transpose();
    else out.normals.row(g) << 0, 0, 1;
    ++out.fallback_normals;
  }
}

}  // namespace

CornerNormals compute_corner_normals(const RowMatrixX3d& positions,
                                     const std::vector<Triangle>& triangles,
                                     double crease_angle_deg, const EdgeAdjacency* adjacency) {
  const size_t nf = triangles.size();
  std::vector<Eigen::Vector3d> face_normal(nf);
  std::vector<std::array<double, 3>> corner_angle(nf);
  for (size_t f = 0; f < nf; ++f) {
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k) p[k] = positions.row(triangles[f][k]).transpose();
    Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
    double len = n.norm();
    face_normal[f] = (len > 0 && std::isfinite(len)) ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d a = p[(k + 1) % 3] - p[k], b = p[(k + 2) % 3] - p[k];
      double an = a.norm(), bn = b.norm();
      corner_angle[f][k] =
          (an > 0 && bn > 0) ? std::acos(std::clamp(a.dot(b) / (an * bn), -1.0, 1.0)) : 0.0;
    }
  }

  const double cos_crease = std::cos(std::clamp(crease_angle_deg, 0.0, 180.0) * M_PI / 180.0);
  EdgeAdjacency own;
  if (!adjacency) own = edge_adjacency(triangles);
  const EdgeAdjacency& adj = adjacency ? *adjacency : own;
  UnionFind uf(nf * 3);
  for (size_t e = 0; e < adj.num_edges(); ++e) {
    if (adj.valence(e) != 2) continue;  // boundary and non-manifold edges are creases
    const uint32_t h = adj.edge_begin(e)[0], g = adj.edge_begin(e)[1];
    const bool opposite = half_edge_tail(triangles, h) != half_edge_tail(triangles, g);
    const Eigen::Vector3d &nh = face_normal[h / 3], &ng = face_normal[g / 3];
    const bool degenerate = nh.isZero() || ng.isZero();
    if (opposite && (degenerate || nh.dot(ng) >= cos_crease)) {
      // h runs a->b from corner slot h to h's next corner; g runs b->a.
      const uint32_t h1 = h / 3 * 3 + (h % 3 + 1) % 3, g1 = g / 3 * 3 + (g % 3 + 1) % 3;
      uf.unite(h, g1);
      uf.unite(h1, g);
    }
  }

  CornerNormals out;
  out.group.assign(nf * 3, 0);
  std::vector<uint32_t> root_to_group(nf * 3, UINT32_MAX);
  std::vector<Eigen::Vector3d> sum;
  for (uint32_t c = 0; c < nf * 3; ++c) {
    uint32_t r = uf.find(c);
    if (root_to_group[r] == UINT32_MAX) {
      root_to_group[r] = static_cast<uint32_t>(sum.size());
      sum.push_back(Eigen::Vector3d::Zero());
    }
    uint32_t g = root_to_group[r];
    out.group[c] = g;
    sum[g] += corner_angle[c / 3][c % 3] * face_normal[c / 3];
  }

  out.normals.resize(static_cast<Eigen::Index>(sum.size()), 3);
  for (size_t g = 0; g < sum.size(); ++g) {
    const double len = sum[g].norm();
    if (len > 1e-300 && std::isfinite(len)) out.normals.row(static_cast<Eigen::Index>(g)) = (sum[g] / len).transpose();
    else out.normals.row(static_cast<Eigen::Index>(g)).setConstant(std::nan(""));
  }
  fill_degenerate_groups(positions, triangles, out);
  return out;
}

}  // namespace prtsub
