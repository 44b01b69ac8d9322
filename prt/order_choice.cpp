// Only the order a scene needs. A vertex's transfer t has energy in every band; an asset of order
// N keeps bands 0..N−1 and drops the rest, and under the worst unit-power light the radiance it
// then gets wrong is ‖t_{l≥N}‖ (orthonormal bands), the same metric eval reports. More bands are
// not free: each coefficient carries the estimate's noise, so an order-N asset's noise grows with
// N while its truncation falls. The default keeps the lowest N whose truncation is below its own
// noise: past it, the bands added are mostly noise at the bake's rays.
//
// The pilot traces a subset of the vertices twice at max_order with two independent seeds, a
// and b. Per coefficient, E[((a+b)/2)²] = t² + var/2 and E[(a−b)²] = 2 var, so
// ((a+b)/2)² − (a−b)²/4 estimates t² without the noise's bias, and (a−b)²/2 the variance of one
// estimate at the bake's rays. Summed over bands ≥ N (truncation) or < N (noise) and averaged over
// the points, both are RMS in eval's unit, ‖t_unshadowed‖ at max_order. The energy beyond max_order
// is not seen; the clamped cosine's bands fall as l^−2.5, so it is the smallest of what is left.
//
// A light L turned by a uniformly random rotation R gives a point the radiance error
// Σ_{l≥N} Σ_m (R L)_lm t_lm, whose mean square is Σ_{l≥N} P_l E_l / (2l + 1) (P_l: the light's
// power in band l, E_l: the point's; rotations mix a band's 2l + 1 coefficients uniformly). So
// a light enters only as band weights P_l / (2l + 1): a sky's fall fast and keep few bands, a
// small sun's stay near 1, as in eval's worst-light metric, which is the weights all 1.
#include "prtsub/prt/order_choice.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {

OrderChoice choose_order(const RayScene& scene, const RowMatrixX3d& mesh_points, const RowMatrixX3d& normals, const RowMatrixX3d& offsets,
                         const TransferOptions& transfer, const OrderChoiceOptions& o) {
  if (o.max_order < 2 || o.max_order > kMaxShOrder)
    throw InputError("--max-order must be between 2 and " + std::to_string(kMaxShOrder) + ", got " + std::to_string(o.max_order));
  if (!(o.tolerance_percent >= 0) || !std::isfinite(o.tolerance_percent))
    throw InputError("--order-tolerance must be a non-negative percentage");
  if (o.pilot_points < 1) throw InputError("order choice: the pilot needs at least one point");
  if (transfer.rays < 2) throw InputError("--order auto needs at least 2 rays per vertex to measure their noise");
  Stopwatch clock;
  const Eigen::Index V = mesh_points.rows();
  const Eigen::Index P = std::min<Eigen::Index>(V, static_cast<Eigen::Index>(o.pilot_points));
  RowMatrixX3d points(P, 3), pn(P, 3), po(P, 3);
  std::vector<uint64_t> streams(static_cast<size_t>(P));
  for (Eigen::Index i = 0; i < P; ++i) {
    const Eigen::Index v = P == V ? i : static_cast<Eigen::Index>((static_cast<double>(i) + 0.5) * static_cast<double>(V) / static_cast<double>(P));
    points.row(i) = mesh_points.row(v), pn.row(i) = normals.row(v), po.row(i) = offsets.row(v);
    streams[static_cast<size_t>(i)] = static_cast<uint64_t>(v);
  }
  TransferOptions t = transfer;
  t.order = o.max_order, t.streams = &streams, t.log = nullptr, t.first_ray = 0, t.first_round_rays = 0;
  TransferStats sa, sb;
  t.seed = mix64(transfer.seed ^ 0x0BDE5EEDull);
  const RowMatrixXd a = shadowed_transfer(scene, points, pn, t, &sa, {}, &po);
  t.seed = mix64(transfer.seed ^ 0x0BDE5EEEull);
  const RowMatrixXd b = shadowed_transfer(scene, points, pn, t, &sb, {}, &po);
  // Per band: the signal's energy (bias-corrected) and one estimate's variance, summed over points.
  const int M = o.max_order;
  std::vector<double> energy(static_cast<size_t>(M), 0.0), variance(static_cast<size_t>(M), 0.0);
  for (Eigen::Index i = 0; i < P; ++i)
    for (int l = 0; l < M; ++l)
      for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
        const double mean = (a(i, k) + b(i, k)) / 2, d = a(i, k) - b(i, k);
        energy[static_cast<size_t>(l)] += mean * mean - d * d / 4;
        variance[static_cast<size_t>(l)] += d * d / 2;
      }
  std::vector<double> weight(static_cast<size_t>(M), 1.0);
  if (!o.band_power.empty()) {
    if (o.band_power.size() < static_cast<size_t>(M)) throw InputError("order choice: the light's band power needs max_order bands");
    for (int l = 0; l < M; ++l) {
      const double p = o.band_power[static_cast<size_t>(l)];
      if (!(p >= 0) || !std::isfinite(p)) throw InputError("order choice: the light's band power must be finite and non-negative");
      weight[static_cast<size_t>(l)] = p / (2 * l + 1);
    }
  }
  // The unit: an unshadowed point's, ‖t_unshadowed‖ with the same weights.
  double unit2 = 0;
  for (int l = 0; l < M; ++l) unit2 += weight[static_cast<size_t>(l)] * clamped_cosine_band(l) * clamped_cosine_band(l) * (2 * l + 1) / (4 * M_PI);
  if (!(unit2 > 0)) throw InputError("order choice: the light has no power in the bands an unshadowed point sees");
  OrderChoice c;
  const double unit = std::sqrt(unit2), n = static_cast<double>(P);
  for (int N = 1; N <= M; ++N) {
    double tail = 0, noise = 0;
    for (int l = N; l < M; ++l) tail += weight[static_cast<size_t>(l)] * energy[static_cast<size_t>(l)];
    for (int l = 0; l < N; ++l) noise += weight[static_cast<size_t>(l)] * variance[static_cast<size_t>(l)];
    c.truncation_percent.push_back(100 * std::sqrt(std::max(tail, 0.0) / n) / unit);
    c.noise_percent.push_back(100 * std::sqrt(noise / n) / unit);
  }
  // Order M's own truncation (bands ≥ M) is not seen: it is chosen only when nothing below is.
  c.order = M, c.reached = false;
  for (int N = 1; N < M; ++N) {
    const double tolerance = o.tolerance_percent > 0 ? o.tolerance_percent : c.noise_percent[static_cast<size_t>(N - 1)];
    if (c.truncation_percent[static_cast<size_t>(N - 1)] <= tolerance) {
      c.order = N, c.reached = true, c.tolerance_percent = tolerance;
      break;
    }
  }
  if (!c.reached) c.tolerance_percent = o.tolerance_percent > 0 ? o.tolerance_percent : c.noise_percent.back();
  c.points = static_cast<size_t>(P);
  c.rays = sa.rays + sb.rays;
  c.seconds = clock.total();
  return c;
}

}  // namespace prtsub
