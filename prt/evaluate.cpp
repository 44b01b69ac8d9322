// Measuring error (PIPELINE.md): at a point, the worst unit-power light changes radiance by
// exactly ‖Δt‖, so the surface RMS of ‖g − t_ref‖ / ‖t_unshadowed‖ is both the least-squares
// objective and a worst-light error. Points are area-stratified: systematic sampling of the
// cumulative area with one seeded offset gives each triangle a share of points proportional to
// its area without clumping, and every asset baked from a source is judged on the same points.
// Each point's transfer in the asset is found through source_face: only faces that lie in the
// point's input triangle are candidates, so refinement of any kind can be judged. A simplified
// asset's faces no longer lie in input triangles; there each point is located at its closest
// point on the asset's surface instead (Embree's point queries).
#include "prtsub/prt/evaluate.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "prtsub/prt/closest_point.h"
#include "prtsub/prt/path_transfer.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {

double unshadowed_norm(int order) {
  double s = 0;
  for (int l = 0; l < order; ++l) s += clamped_cosine_band(l) * clamped_cosine_band(l) * (2 * l + 1) / (4 * M_PI);
  return std::sqrt(s);
}

Reference make_reference(const Mesh& src, const RayScene& scene, const ReferenceOptions& o, const ProgressFn& progress) {
  if (o.points == 0) throw InputError("reference: the point count must be positive");
  std::vector<double> cumulative(src.num_faces() + 1, 0.0);
  for (size_t f = 0; f < src.num_faces(); ++f) {
    const Triangle& t = src.triangles[f];
    cumulative[f + 1] = cumulative[f] + triangle_area(src.point(t[0]), src.point(t[1]), src.point(t[2]));
  }
  const double total = cumulative.back();
  if (!(total > 0)) throw InputError("eval: the source has no area");
  Reference ref;
  ref.rays = o.rays;
  const Eigen::Index n = static_cast<Eigen::Index>(o.points);
  ref.points.resize(n, 3);
  ref.normals.resize(n, 3);
  ref.source_face.resize(o.points);
  const RowMatrixX3d corners = vertex_positions(src);
  Rng offset(o.seed, 0);
  const double r0 = offset.uniform();
  for (Eigen::Index i = 0; i < n; ++i) {
    const double target = (static_cast<double>(i) + r0) / static_cast<double>(n) * total;
    size_t f = static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin()) - 1;
    f = std::min(f, src.num_faces() - 1);
    Rng rng(o.seed, 1 + static_cast<uint64_t>(i));
    double u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Triangle& t = src.triangles[f];
    // The point on the surface itself, as the bake samples vertices: transfer is defined at
    // surface points, and a refined asset must converge to this reference. (render --reference
    // lifts points towards the smooth surface for display; here that would leave errors near
    // contacts that no refinement of the flat surface could remove.)
    ref.points.row(i) = (1 - u - v) * corners.row(t[0]) + u * corners.row(t[1]) + v * corners.row(t[2]);
    Eigen::Vector3d nrm = (1 - u - v) * src.normals.row(t[0]) + u * src.normals.row(t[1]) + v * src.normals.row(t[2]);
    if (!(nrm.norm() > 1e-12)) nrm = (src.point(t[1]) - src.point(t[0])).cross(src.point(t[2]) - src.point(t[0]));
    if (!(nrm.norm() > 0)) nrm = Eigen::Vector3d::UnitZ();
    ref.normals.row(i) = nrm.normalized().transpose();
    ref.source_face[static_cast<size_t>(i)] = src.source_face[f];
  }
  TransferOptions to;
  to.order = o.order, to.rays = o.rays, to.seed = o.seed + 1, to.threads = o.threads;
  ref.transfer = shadowed_transfer(scene, ref.points, ref.normals, to, nullptr, progress);
  const int channels = o.colour ? 3 : 1;  // RGB: every channel's direct light is the same
  if (channels == 3) ref.transfer = ref.transfer.replicate(1, 3).eval();
  // Bounced light: paths through the source, from the reference points (their own seeds).
  const PathSurface surface{corners, src.normals, src.triangles};
  PathOptions po;
  po.order = o.order, po.paths = o.paths > 0 ? o.paths : o.rays, po.bounces = o.bounces, po.albedo = o.albedo;
  po.seed = o.seed + 3, po.threads = o.threads, po.colour = o.colour;
  if (o.bounces > 0) {
    const Stopwatch clock;
    ref.transfer += path_traced_transfer(scene, surface, ref.points, ref.normals, po, nullptr, nullptr, progress);
    ref.bounces = o.bounces, ref.paths = po.paths, ref.seconds_bounce = clock.total();
  }
  // The reference's own noise: trace the first points again with other seeds.
  const Eigen::Index m = std::min<Eigen::Index>(n, static_cast<Eigen::Index>(o.noise_points));
  if (m > 0) {
    to.seed = o.seed + 2;
    RowMatrixXd again = shadowed_transfer(scene, ref.points.topRows(m), ref.normals.topRows(m), to).replicate(1, channels);
    po.seed = o.seed + 4;
    if (o.bounces > 0) again += path_traced_transfer(scene, surface, ref.points.topRows(m), ref.normals.topRows(m), po);
    const double diff = (again - ref.transfer.topRows(m)).rowwise().squaredNorm().mean();
    ref.noise_floor = std::sqrt(diff / 2 / channels) / unshadowed_norm(o.order);  // one estimate's RMS error (over channels)
  }
  return ref;
}

namespace {

// Which columns eval compares: per channel the first K coefficients both hold (a reference of
// another order compares the bands both have), and the unit.
struct Compared {
  int channels = 1;
  Eigen::Index K = 0, asset_stride = 0, reference_stride = 0;
  double unit = 1;
};

Compared compared_columns(const RowMatrixXd& transfer, const RowMatrixXd& reference) {
  const int ca = std::max(transfer_channels(transfer.cols()), 1), cr = std::max(transfer_channels(reference.cols()), 1);
  if (ca != cr)
    throw InputError(std::string("eval: the asset's transfer is ") + (ca == 3 ? "RGB" : "grey") + " and the reference's " + (cr == 3 ? "RGB" : "grey") +
                     " (judge a coloured bounce against a coloured reference)");
  Compared c;
  c.channels = ca, c.asset_stride = transfer.cols() / ca, c.reference_stride = reference.cols() / cr;
  c.K = std::min(c.asset_stride, c.reference_stride);
  c.unit = unshadowed_norm(static_cast<int>(std::lround(std::sqrt(static_cast<double>(c.K)))));
  return c;
}

// ‖g(p) − t_ref(p)‖ over the compared coefficients (RMS over channels): the asset's transfer
// interpolated in face t with weights w, against reference row i.
double interpolation_error(const RowMatrixXd& transfer, const Triangle& t, const Eigen::Vector3d& w, const RowMatrixXd& reference,
                           Eigen::Index i, const Compared& c) {
  double e2 = 0;
  for (int ch = 0; ch < c.channels; ++ch)
    for (Eigen::Index k = 0; k < c.K; ++k) {
      const Eigen::Index a = ch * c.asset_stride + k;
      const double g = w[0] * transfer(t[0], a) + w[1] * transfer(t[1], a) + w[2] * transfer(t[2], a);
      const double d = g - reference(i, ch * c.reference_stride + k);
      e2 += d * d;
    }
  return std::sqrt(e2 / c.channels);
}

// RMS and 95th percentile of the points' errors (relative), in percent.
void summarize(std::vector<double>& err, EvalResult& r) {
  r.points = err.size();
  if (err.empty()) throw InputError("eval: no reference point could be located in the asset (was the asset baked from this source?)");
  double s = 0;
  for (double e : err) s += e * e;
  r.rms_percent = 100 * std::sqrt(s / static_cast<double>(err.size()));
  std::sort(err.begin(), err.end());
  r.p95_percent = 100 * err[std::min(err.size() - 1, static_cast<size_t>(0.95 * static_cast<double>(err.size())))];
}

}  // namespace

EvalResult evaluate(const Reference& ref, const RowMatrixX3d& positions, const std::vector<Triangle>& triangles,
                    const std::vector<uint32_t>& source_face, const RowMatrixXd& transfer) {
  const Compared K = compared_columns(transfer, ref.transfer);
  std::unordered_map<uint32_t, std::vector<uint32_t>> faces_of;
  for (uint32_t f = 0; f < triangles.size(); ++f) faces_of[source_face[f]].push_back(f);
  const double unit = K.unit;
  EvalResult r;
  r.reference_rays = ref.rays;
  r.noise_floor_percent = 100 * ref.noise_floor;
  std::vector<double> err;
  err.reserve(static_cast<size_t>(ref.points.rows()));
  for (Eigen::Index i = 0; i < ref.points.rows(); ++i) {
    auto it = faces_of.find(ref.source_face[static_cast<size_t>(i)]);
    if (it == faces_of.end()) {
      ++r.unlocated;
      continue;
    }
    const Eigen::Vector3d p = ref.points.row(i).transpose();
    double best_score = -1e300;
    uint32_t best = 0;
    Eigen::Vector3d best_w;
    for (uint32_t f : it->second) {
      const Triangle& t = triangles[f];
      const Eigen::Vector3d a = positions.row(t[0]), b = positions.row(t[1]), c = positions.row(t[2]);
      const Eigen::Vector3d n = (b - a).cross(c - a);
      const double nn = n.squaredNorm();
      if (!(nn > 0)) continue;
      // Barycentrics of p projected onto the face's plane: signed sub-areas over the area.
      Eigen::Vector3d w(((b - p).cross(c - p)).dot(n) / nn, ((c - p).cross(a - p)).dot(n) / nn,
                        ((a - p).cross(b - p)).dot(n) / nn);
      const double score = w.minCoeff();  // >= 0 inside
      if (score > best_score) best_score = score, best = f, best_w = w;
      if (score >= 0) break;
    }
    if (best_score == -1e300) {
      ++r.unlocated;
      continue;
    }
    // Clamp to the face: a point just outside (rounding, or a moved Loop surface) takes the
    // nearest barycentrics.
    Eigen::Vector3d w = best_w.cwiseMax(0.0);
    w /= w.sum();
    err.push_back(interpolation_error(transfer, triangles[best], w, ref.transfer, i, K) / unit);
  }
  summarize(err, r);
  return r;
}

EvalResult evaluate_by_closest_point(const Reference& ref, const RowMatrixX3d& positions, const std::vector<Triangle>& triangles,
                                     const RowMatrixXd& transfer, int threads, std::vector<double>* point_errors) {
  const Compared K = compared_columns(transfer, ref.transfer);
  const double unit = K.unit;
  Mesh m;  // the asset's faces as a mesh whose render vertices are its positions
  m.positions = positions;
  m.vertex_position.resize(static_cast<size_t>(positions.rows()));
  for (size_t i = 0; i < m.vertex_position.size(); ++i) m.vertex_position[i] = static_cast<uint32_t>(i);
  m.triangles = triangles;
  const std::vector<SurfaceLocation> at = closest_points(m, ref.points, threads, &ref.normals);
  EvalResult r;
  r.reference_rays = ref.rays;
  r.noise_floor_percent = 100 * ref.noise_floor;
  std::vector<double> err;
  err.reserve(at.size());
  for (size_t i = 0; i < at.size(); ++i) {
    err.push_back(interpolation_error(transfer, triangles[at[i].face], at[i].barycentric, ref.transfer,
                                      static_cast<Eigen::Index>(i), K) / unit);
  }
  if (point_errors) *point_errors = err;
  summarize(err, r);
  return r;
}

}  // namespace prtsub
