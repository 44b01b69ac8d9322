// Surface samples for the least-squares fit (Kavan et al. 2011, section 3.3).
//
// The fit needs b_i = ∫ h_i f, estimated per face: ∫_t h_i f ≈ a_t/n_t Σ_{j∈t} h_i(p_j) f(p_j).
// Splitting the integral by face keeps the estimate unbiased for any allocation as long as every
// face with area has a sample, which the per-face minimum guarantees; spending the rest by area
// keeps the sampling density uniform, which is what minimises variance for a smooth f. Inside a
// face the n points are a Fibonacci rank-1 lattice in the unit square, shifted by one seeded
// random vector and folded onto the triangle: each point is uniform on the face, and the set
// covers it evenly, so a face's samples do not clump as independent ones would.
#include "prtsub/prt/surface_samples.h"

#include <cmath>

#include "prtsub/prt/sampling.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

SurfacePoint surface_point(const Mesh& mesh, size_t face, const Eigen::Vector3d& w) {
  const Triangle& t = mesh.triangles[face];
  const Eigen::Vector3d a = mesh.point(t[0]), b = mesh.point(t[1]), c = mesh.point(t[2]);
  Eigen::Vector3d face_normal = (b - a).cross(c - a);
  face_normal = face_normal.norm() > 0 ? Eigen::Vector3d(face_normal.normalized()) : Eigen::Vector3d::UnitZ();
  SurfacePoint p;
  p.point = w[0] * a + w[1] * b + w[2] * c;
  const Eigen::Vector3d n = w[0] * mesh.normals.row(t[0]) + w[1] * mesh.normals.row(t[1]) + w[2] * mesh.normals.row(t[2]);
  p.normal = n.norm() > 1e-12 ? Eigen::Vector3d(n.normalized()) : face_normal;
  p.offset = face_normal.dot(p.normal) >= 0 ? face_normal : Eigen::Vector3d(-face_normal);
  return p;
}

SurfaceSamples make_surface_samples(const Mesh& mesh, const SampleOptions& o) {
  return make_surface_samples(mesh, o, std::vector<double>());
}

SurfaceSamples make_surface_samples(const Mesh& mesh, const SampleOptions& o, const std::vector<double>& face_weight) {
  const bool weighted = !face_weight.empty();
  if (weighted && face_weight.size() != mesh.num_faces()) throw InputError("samples: one weight per face expected");
  for (double w : face_weight)
    if (!(w >= 0) || !std::isfinite(w)) throw InputError("samples: face weights must be finite and non-negative");
  if (!(o.per_triangle >= 0) || !std::isfinite(o.per_triangle) || !(o.density >= 0) || !std::isfinite(o.density))
    throw InputError("samples: counts must be finite and non-negative");
  const size_t F = mesh.num_faces();
  std::vector<double> area(F), share(F);  // share: the area the extra samples are spread by
  double total_area = 0, total_share = 0;
  for (size_t f = 0; f < F; ++f) {
    const Triangle& t = mesh.triangles[f];
    area[f] = triangle_area(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]));
    if (!std::isfinite(area[f])) area[f] = 0;
    total_area += area[f];
  }
  // Faces below this are numerically flat: a sample there would carry no weight in b.
  const double tiny = 1e-14 * total_area / static_cast<double>(std::max<size_t>(F, 1));
  std::vector<size_t> count(F, 0);
  size_t fixed = 0;
  SurfaceSamples s;
  if (weighted) s.interpolated.assign(F, 0);
  for (size_t f = 0; f < F; ++f) {
    if (!(area[f] > tiny)) continue;
    if (weighted && face_weight[f] == 0) {
      s.interpolated[f] = 1;
      continue;
    }
    count[f] = o.min_per_triangle, fixed += o.min_per_triangle;
    share[f] = weighted ? area[f] * face_weight[f] : area[f];
    total_share += share[f];
  }
  const double wanted = o.density > 0 ? o.density * total_area : o.per_triangle * static_cast<double>(F);
  if (wanted > 4e9) throw InputError("samples: " + std::to_string(wanted) + " samples requested; at most 4e9");
  const size_t extra = wanted > static_cast<double>(fixed) ? static_cast<size_t>(std::llround(wanted)) - fixed : 0;
  if (extra > 0 && total_share > 0) {
    // Systematic sampling of the cumulative share: sample k lands at (k + r) / extra of it.
    Rng rng(o.seed, 0);
    const double r = rng.uniform(), step = total_share / static_cast<double>(extra);
    double cumulative = 0;
    size_t k = 0;
    for (size_t f = 0; f < F && k < extra; ++f) {
      cumulative += share[f];
      while (k < extra && (static_cast<double>(k) + r) * step < cumulative) ++count[f], ++k;
    }
    for (size_t f = F; k < extra && f-- > 0;)  // rounding left some over: give them to the last face with a share
      if (share[f] > 0) count[f] += extra - k, k = extra;
  }

  s.begin.assign(F + 1, 0);
  for (size_t f = 0; f < F; ++f) s.begin[f + 1] = s.begin[f] + count[f];
  const size_t S = s.begin[F];
  const auto n = static_cast<Eigen::Index>(S);
  s.points.resize(n, 3), s.normals.resize(n, 3), s.offsets.resize(n, 3), s.barycentric.resize(n, 3);
  s.face.resize(S), s.weight.resize(S);
  const double golden = 0.6180339887498949;
  for (size_t f = 0; f < F; ++f) {
    if (count[f] == 0) continue;
    Rng rng(o.seed, 1 + f);
    const double su = rng.uniform(), sv = rng.uniform();
    for (size_t k = 0; k < count[f]; ++k) {
      double u = std::fmod((static_cast<double>(k) + su) / static_cast<double>(count[f]), 1.0);
      double v = std::fmod(static_cast<double>(k) * golden + sv, 1.0);
      if (u + v > 1) u = 1 - u, v = 1 - v;  // fold the square onto the triangle: measure-preserving
      const Eigen::Vector3d w(1 - u - v, u, v);
      const size_t j = s.begin[f] + k;
      const auto i = static_cast<Eigen::Index>(j);
      s.face[j] = static_cast<uint32_t>(f);
      s.weight[j] = area[f] / static_cast<double>(count[f]);
      s.barycentric.row(i) = w.transpose();
      const SurfacePoint at = surface_point(mesh, f, w);
      s.points.row(i) = at.point.transpose(), s.normals.row(i) = at.normal.transpose(), s.offsets.row(i) = at.offset.transpose();
    }
  }
  return s;
}

SurfaceSamples merge_surface_samples(const SurfaceSamples& a, const SurfaceSamples& b) {
  if (a.begin.size() != b.begin.size() || a.begin.empty()) throw InputError("samples: cannot merge sample sets of different meshes");
  const size_t F = a.begin.size() - 1;
  SurfaceSamples s;
  s.begin.assign(F + 1, 0);
  for (size_t f = 0; f < F; ++f) s.begin[f + 1] = s.begin[f] + (a.begin[f + 1] - a.begin[f]) + (b.begin[f + 1] - b.begin[f]);
  const size_t S = s.begin[F];
  const auto n = static_cast<Eigen::Index>(S);
  s.points.resize(n, 3), s.normals.resize(n, 3), s.offsets.resize(n, 3), s.barycentric.resize(n, 3);
  s.face.resize(S), s.weight.resize(S);
  for (size_t f = 0; f < F; ++f) {
    const size_t na = a.begin[f + 1] - a.begin[f], nb = b.begin[f + 1] - b.begin[f];
    if (na + nb == 0) continue;
    // The face's area from either set's weights: weight × count is the area.
    const double area = na ? a.weight[a.begin[f]] * double(na) : b.weight[b.begin[f]] * double(nb);
    size_t k = s.begin[f];
    for (const auto* src : {&a, &b})
      for (size_t j = src->begin[f]; j < src->begin[f + 1]; ++j, ++k) {
        const auto r = static_cast<Eigen::Index>(j), t = static_cast<Eigen::Index>(k);
        s.points.row(t) = src->points.row(r), s.normals.row(t) = src->normals.row(r);
        s.offsets.row(t) = src->offsets.row(r), s.barycentric.row(t) = src->barycentric.row(r);
        s.face[k] = static_cast<uint32_t>(f);
        s.weight[k] = area / double(na + nb);
      }
  }
  const std::vector<char>& flags = a.interpolated.empty() ? b.interpolated : a.interpolated;
  if (!flags.empty()) {
    s.interpolated = flags;
    for (size_t f = 0; f < F; ++f)
      if (s.begin[f + 1] > s.begin[f]) s.interpolated[f] = 0;
  }
  return s;
}

}  // namespace prtsub
