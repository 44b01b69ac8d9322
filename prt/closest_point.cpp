// Closest points by Embree's BVH point queries.
//
// The mesh goes into a RayScene (local float frame, one shared device). A query starts with an
// infinite radius; for every triangle whose box the BVH reaches, the callback finds the
// triangle's closest point in double precision on the mesh's own positions (Ericson's region
// test: a vertex, an edge or the interior) and shrinks the radius to it, so the walk prunes
// everything farther. The radius is padded by 10⁻⁶ of the diagonal, well above the float
// rounding of the local frame, so the walk never prunes a triangle as near as the best; among
// equally near triangles the lower index wins, whatever order the walk visits them in.
#include "prtsub/prt/closest_point.h"

#include <cmath>
#include <limits>

#include "prtsub/prt/parallel.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = va + vb + vc;
  if (!(denom > 0)) return {1, 0, 0};  // no area: a corner is as good as any point
  const double v = vb / denom, w = vc / denom;
  return {1 - v - w, v, w};
}

namespace {

struct Query {
  const Mesh* mesh;
  double pad;
  Eigen::Vector3d p;
  const Eigen::Vector3d* facing = nullptr;  // only faces whose winding normal has a positive dot with it
  SurfaceLocation best;
  double best_d2 = std::numeric_limits<double>::infinity();
};

bool visit(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<Query*>(args->userPtr);
  const uint32_t f = args->primID;
  const Triangle& t = q->mesh->triangles[f];
  const Eigen::Vector3d a = q->mesh->point(t[0]), b = q->mesh->point(t[1]), c = q->mesh->point(t[2]);
  if (q->facing && !((b - a).cross(c - a).dot(*q->facing) > 0)) return false;
  const Eigen::Vector3d w = closest_on_triangle(q->p, a, b, c);
  const double d2 = (w[0] * a + w[1] * b + w[2] * c - q->p).squaredNorm();
  if (d2 < q->best_d2 || (d2 == q->best_d2 && f < q->best.face)) {
    q->best_d2 = d2;
    q->best.face = f, q->best.barycentric = w;
    const float r = static_cast<float>(std::sqrt(d2) + q->pad);
    if (r < args->query->radius) {
      args->query->radius = r;
      return true;
    }
  }
  return false;
}

}  // namespace

std::vector<SurfaceLocation> closest_points(const Mesh& mesh, const RowMatrixX3d& points, int threads, const RowMatrixX3d* normals) {
  if (mesh.num_faces() == 0) throw InputError("closest points: the mesh has no faces");
  return closest_points(mesh, RayScene(mesh.positions, position_triangles(mesh)), points, threads, normals);
}

std::vector<SurfaceLocation> closest_points(const Mesh& mesh, const RayScene& scene, const RowMatrixX3d& points, int threads,
                                            const RowMatrixX3d* normals) {
  if (mesh.num_faces() == 0) throw InputError("closest points: the mesh has no faces");
  if (!points.allFinite()) throw InputError("closest points: a query point is not finite");
  if (normals && normals->rows() != points.rows()) throw InputError("closest points: one normal per query point expected");
  std::vector<SurfaceLocation> out(static_cast<size_t>(points.rows()));
  parallel_range<Eigen::Index>(points.rows(), threads, 256, [&](const tbb::blocked_range<Eigen::Index>& range) {
    for (Eigen::Index i = range.begin(); i != range.end(); ++i) {
      const Eigen::Vector3d n = normals ? Eigen::Vector3d(normals->row(i).transpose()) : Eigen::Vector3d::Zero();
      Query q{&mesh, 1e-6 * scene.diagonal(), points.row(i).transpose(), normals ? &n : nullptr, {}};
      const Eigen::Vector3f local = scene.to_local(q.p);
      q.best.face = UINT32_MAX;
      // Facing faces first; where none faces the point's way (or none was asked for), any face.
      for (int pass = normals ? 0 : 1; pass < 2 && (pass == 0 || q.best.face == UINT32_MAX); ++pass) {
        if (pass == 1) q.facing = nullptr;
        q.best = SurfaceLocation{};
        q.best.face = UINT32_MAX;
        q.best_d2 = std::numeric_limits<double>::infinity();
        RTCPointQuery query;
        query.x = local.x(), query.y = local.y(), query.z = local.z(), query.time = 0;
        query.radius = std::numeric_limits<float>::infinity();
        RTCPointQueryContext context;
        rtcInitPointQueryContext(&context);
        rtcPointQuery(scene.handle(), &query, &context, visit, &q);
      }
      q.best.distance = std::sqrt(q.best_d2);
      out[size_t(i)] = q.best;
    }
  });
  scene.check("closest-point queries");
  for (const SurfaceLocation& s : out)
    if (s.face == UINT32_MAX) throw EmbreeError("closest points: a query found no face");
  return out;
}

}  // namespace prtsub
