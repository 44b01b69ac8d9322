// The asset's error, measured on held-out samples (issue 11, point 3: a predicted error that
// `prtsub eval` confirms).
//
// The pilot traces its samples with rays of their own, so they are independent of the vertex
// rays, the fit's samples and the second round: a hold-out set. At a held-out point p with
// traced value f̂ = f(p) + ε (E ε = 0, E‖ε‖² = v, v from the estimator's two ray halves) and
// the asset's interpolated value g(p), E‖f̂ − g‖² = E‖f − g‖² + v: so ‖f̂ − g‖² − v estimates the
// asset's squared error at p, noise and interpolation error together, and the area-weighted
// mean over the set estimates eval's mean. Its standard error comes from the terms' spread.
// A bounced asset is judged against bounced light: the held-out samples' references gain it from
// paths through the surface (bounced_holdout), each with its own variance, the same way.
// Caveat: which faces the fit sampled depended on the pilot's values, so the set is not quite
// independent of the asset there (BENCHMARKS.md measures the prediction against eval).
#include "prtsub/prt/error_estimate.h"

#include <cmath>

#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/surface_samples.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

// RGB transfer holds three blocks of N² values (docs/sh_convention.md, "Colour").
int value_channels(Eigen::Index columns) {
  const auto square = [](Eigen::Index n) {
    const auto r = static_cast<Eigen::Index>(std::lround(std::sqrt(static_cast<double>(n))));
    return n > 0 && r * r == n;
  };
  if (square(columns)) return 1;
  if (columns % 3 == 0 && square(columns / 3)) return 3;  // 3·N² is never a square
  throw InputError("hold-out error: " + std::to_string(columns) + " values per point are neither N² nor 3·N²");
}

// The held-out samples' points, normals and ray offsets, as the pilot placed them.
void holdout_points(const Mesh& mesh, const Holdout& h, const char* what, RowMatrixX3d& points, RowMatrixX3d& normals, RowMatrixX3d& offsets) {
  const auto n = static_cast<Eigen::Index>(h.size());
  points.resize(n, 3), normals.resize(n, 3), offsets.resize(n, 3);
  for (Eigen::Index k = 0; k < n; ++k) {
    const uint32_t f = h.face[static_cast<size_t>(k)];
    if (f >= mesh.num_faces()) throw InputError(std::string(what) + ": a sample's face is not on the mesh");
    const SurfacePoint p = surface_point(mesh, f, h.barycentric.row(k).transpose());
    points.row(k) = p.point.transpose(), normals.row(k) = p.normal.transpose(), offsets.row(k) = p.offset.transpose();
  }
}

}  // namespace

ErrorEstimate holdout_error(const Mesh& mesh, const Holdout& h, const RowMatrixXd& values) {
  if (static_cast<size_t>(values.rows()) != mesh.num_vertices()) throw InputError("hold-out error: one row of values per vertex expected");
  const size_t n = h.size();
  ErrorEstimate e;
  if (n == 0) return e;
  if (h.values.cols() != values.cols()) throw InputError("hold-out error: the values' order does not match the samples'");
  double sw = 0, sum = 0, sum2 = 0, sw2 = 0;
  for (size_t k = 0; k < n; ++k) {
    if (h.face[k] >= mesh.num_faces() || !std::isfinite(h.variance[k])) continue;
    const Triangle& t = mesh.triangles[h.face[k]];
    const auto r = static_cast<Eigen::Index>(k);
    Eigen::VectorXd d = h.values.row(r).cast<double>().transpose();
    for (int c = 0; c < 3; ++c) d -= h.barycentric(r, c) * values.row(t[c]).transpose();
    const double term = d.squaredNorm() - h.variance[k], w = h.weight[k];
    sw += w, sum += w * term, sum2 += w * term * term, sw2 += w * w;
    ++e.samples;
  }
  if (!(sw > 0)) return e;
  const double mean = sum / sw;
  // The weighted mean's variance: Σw²·s² / (Σw)², s² the terms' weighted variance.
  const double spread = std::max(0.0, sum2 / sw - mean * mean);
  double se2 = std::sqrt(sw2 * spread) / sw;
  const int channels = value_channels(values.cols());
  const int order = static_cast<int>(std::lround(std::sqrt(static_cast<double>(values.cols() / channels))));
  const double unit = unshadowed_norm(order), e2 = std::max(0.0, mean / channels);  // RGB: the RMS over channels, as eval
  e.percent = 100 * std::sqrt(e2) / unit;
  // δE = δ(E²) / 2E; near 0 the bound √se2 is the honest one.
  se2 /= channels;
  e.standard_error = 100 * (e2 > se2 ? se2 / (2 * std::sqrt(e2)) : std::sqrt(se2)) / unit;
  return e;
}

ErrorDifference holdout_difference(const Mesh& mesh, const Holdout& h, const RowMatrixXd& a, const RowMatrixXd& b) {
  if (static_cast<size_t>(a.rows()) != mesh.num_vertices() || a.rows() != b.rows() || a.cols() != b.cols())
    throw InputError("hold-out difference: two sets of values of one row per vertex expected");
  ErrorDifference d;
  const size_t n = h.size();
  if (n == 0) return d;
  if (h.values.cols() != a.cols()) throw InputError("hold-out difference: the values' order does not match the samples'");
  double sw = 0, sum = 0, sum2 = 0, sw2 = 0;
  for (size_t k = 0; k < n; ++k) {
    if (h.face[k] >= mesh.num_faces() || !std::isfinite(h.variance[k])) continue;
    const Triangle& t = mesh.triangles[h.face[k]];
    const auto r = static_cast<Eigen::Index>(k);
    Eigen::VectorXd da = h.values.row(r).cast<double>().transpose(), db = da;
    for (int c = 0; c < 3; ++c) da -= h.barycentric(r, c) * a.row(t[c]).transpose(), db -= h.barycentric(r, c) * b.row(t[c]).transpose();
    const double term = da.squaredNorm() - db.squaredNorm(), w = h.weight[k];
    sw += w, sum += w * term, sum2 += w * term * term, sw2 += w * w;
  }
  if (!(sw > 0)) return d;
  d.mean = sum / sw;
  d.standard_error = std::sqrt(sw2 * std::max(0.0, sum2 / sw - d.mean * d.mean)) / sw;
  return d;
}

Holdout holdout_subset(const Holdout& h, size_t count) {
  if (count == 0 || h.size() <= count) return h;
  const size_t stride = (h.size() + count - 1) / count;
  Holdout out;
  out.rays = h.rays;
  const auto n = static_cast<Eigen::Index>((h.size() + stride - 1) / stride);
  out.barycentric.resize(n, 3);
  out.values.resize(n, h.values.cols());
  for (size_t k = 0, j = 0; k < h.size(); k += stride, ++j) {
    const auto a = static_cast<Eigen::Index>(k), b = static_cast<Eigen::Index>(j);
    out.face.push_back(h.face[k]), out.weight.push_back(h.weight[k]), out.variance.push_back(h.variance[k]);
    out.barycentric.row(b) = h.barycentric.row(a), out.values.row(b) = h.values.row(a);
  }
  return out;
}

Holdout sharpen_holdout(const Mesh& mesh, const RayScene& scene, const Holdout& h, const TransferOptions& o, TransferStats* stats,
                        const ProgressFn& progress) {
  if (h.barycentric.rows() != static_cast<Eigen::Index>(h.size())) throw InputError("sharpen hold-out: the samples' arrays differ in length");
  RowMatrixX3d points, normals, offsets;
  holdout_points(mesh, h, "sharpen hold-out", points, normals, offsets);
  return sharpen_holdout_at(points, normals, offsets, scene, h, o, stats, progress);
}

Holdout sharpen_holdout_at(const RowMatrixX3d& points, const RowMatrixX3d& normals, const RowMatrixX3d& offsets, const RayScene& scene,
                           const Holdout& h, const TransferOptions& o, TransferStats* stats, const ProgressFn& progress) {
  const auto n = static_cast<Eigen::Index>(h.size());
  if (h.values.rows() != n || h.variance.size() != h.size() || h.weight.size() != h.size() || points.rows() != n ||
      normals.rows() != n || offsets.rows() != n)
    throw InputError("sharpen hold-out: the samples' arrays differ in length");
  if (h.rays <= 0) throw InputError("sharpen hold-out: the samples' values are not shadowed transfer traced with a known ray count");
  if (o.rays < 1) throw InputError("sharpen hold-out: at least one more ray per sample");
  if (h.values.cols() != o.order * o.order) throw InputError("sharpen hold-out: the values' order does not match the rays'");
  std::vector<double> variance;
  const RowMatrixXd more = shadowed_transfer(scene, points, normals, o, stats, progress, &offsets, &variance);
  // Two independent unbiased estimates, weighted by their rays: still unbiased, and still
  // independent of the asset. (Inverse-variance weights would be closer to optimal, but weights
  // read from the estimates' own noise would correlate with it.)
  const double a = double(h.rays) / double(h.rays + o.rays), b = 1 - a;
  Holdout out = h;
  out.rays = h.rays + o.rays;
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto i = static_cast<size_t>(k);
    out.values.row(k) = (a * h.values.row(k).cast<double>() + b * more.row(k)).cast<float>();
    out.variance[i] = a * a * h.variance[i] + b * b * variance[i];
  }
  return out;
}

Holdout bounced_holdout(const Mesh& mesh, const RayScene& scene, const Holdout& h, const PathOptions& o, TransferStats* stats) {
  const auto n = static_cast<Eigen::Index>(h.size());
  if (h.barycentric.rows() != n || h.values.rows() != n || h.variance.size() != h.size())
    throw InputError("bounced hold-out: the samples' arrays differ in length");
  RowMatrixX3d points, normals, offsets;
  holdout_points(mesh, h, "bounced hold-out", points, normals, offsets);
  const RowMatrixX3d corners = vertex_positions(mesh);
  const PathSurface surface{corners, mesh.normals, mesh.triangles};
  std::vector<double> variance;
  const RowMatrixXd bounced = path_traced_transfer(scene, surface, points, normals, o, &variance, stats);
  const int channels = o.colour ? 3 : 1;
  Holdout out = h;
  out.rays = 0;  // no longer shadowed transfer alone
  out.values = (h.values.cast<double>().replicate(1, channels) + bounced).cast<float>();
  for (size_t k = 0; k < h.size(); ++k) out.variance[k] = channels * h.variance[k] + variance[k];
  return out;
}

}  // namespace prtsub
