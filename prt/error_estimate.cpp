// The asset's error, measured on held-out samples (issue 11, point 3: a predicted error that
// `prtsub eval` confirms).
//
// The pilot traces its samples with rays of their own, so they are independent of the vertex
// rays, the fit's samples and the second round: a hold-out set. At a held-out point p with
// traced value f̂ = f(p) + ε (E ε = 0, E‖ε‖² = v, v from the estimator's two ray halves) and
// the asset's interpolated value g(p), E‖f̂ − g‖² = E‖f − g‖² + v: so ‖f̂ − g‖² − v estimates the
// asset's squared error at p, noise and interpolation error together, and the area-weighted
// mean over the set estimates eval's mean. Its standard error comes from the terms' spread.
// Caveat: which faces the fit sampled depended on the pilot's values, so the set is not quite
// independent of the asset there (BENCHMARKS.md measures the prediction against eval).
#include "prtsub/prt/error_estimate.h"

#include <cmath>

#include "prtsub/prt/evaluate.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

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
  const double spread = std::max(0.0, sum2 / sw - mean * mean), se2 = std::sqrt(sw2 * spread) / sw;
  const int order = static_cast<int>(std::lround(std::sqrt(static_cast<double>(values.cols()))));
  const double unit = unshadowed_norm(order), e2 = std::max(0.0, mean);
  e.percent = 100 * std::sqrt(e2) / unit;
  // δE = δ(E²) / 2E; near 0 the bound √se2 is the honest one.
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

}  // namespace prtsub
