// Progressive least-squares encoding (Roughton 2020, "Progressive Least-Squares Encoding for
// Linear Bases", paper 004, Listing 1).
//
// The least-squares coefficients b of f in a basis B_i satisfy G b = m, G_ij = ∫B_i B_j,
// m_i = ∫B_i f. One Jacobi step solves row i for b_i with the others fixed:
//     b_i ← b_i + ∫B_i (f − Σ_j b_j B_j) / ∫B_i².
// The encoder estimates both integrals from the samples seen so far, one sample at a time: with
// the residual Δ = f(ω_s) − Σ_j b_j B_j(ω_s) at the new sample, a running (Welford) mean gives
//     b_i ← b_i + α (w_s / Σw) B_i(ω_s) Δ / I_i,
// with I_i the running mean of B_i². It is stochastic approximation with a 1/k step; as b
// approaches the fit the residual shrinks, so it acts as its own control variate and, unlike a
// plain projection Σ w f B_i, it does not need the basis to be orthogonal. Gauss–Seidel updates
// Δ after each function's correction (Δ −= (b_i' − b_i) B_i(ω_s), which is the paper's
// Δ·(1 − α s B_i²/I_i) when nothing is clamped, and stays the true residual when the
// non-negative clamp cuts a correction short).
//
// Early on, I_i from a handful of samples can be near zero and blow a correction up; the paper's
// fix starts I_i from a bound on B_i² and blends toward the running mean as 1/k (Interpolated),
// or floors it at the true value (Clamped). Both are options, as is the acceleration α, which
// overshoots on purpose to converge faster.
#include "prtsub/prt/progressive_encoder.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

ProgressiveEncoder::ProgressiveEncoder(int functions, int channels, const ProgressiveOptions& options,
                                       std::vector<double> mean_square, std::vector<double> start)
    : functions_(functions), channels_(channels), options_(options), mean_square_(std::move(mean_square)), start_(std::move(start)) {
  if (functions < 1 || channels < 1)
    throw InputError("progressive encoder: needs at least one function and one channel, got " + std::to_string(functions) + " and " +
                     std::to_string(channels));
  if (mean_square_.size() != size_t(functions) || start_.size() != size_t(functions))
    throw InputError("progressive encoder: one mean square and one start value per function expected");
  for (int i = 0; i < functions; ++i)
    if (!(mean_square_[size_t(i)] > 0) || !(start_[size_t(i)] > 0) || !std::isfinite(mean_square_[size_t(i)]) || !std::isfinite(start_[size_t(i)]))
      throw InputError("progressive encoder: function " + std::to_string(i) + "'s mean square and start value must be positive and finite");
  if (!(options.acceleration > 0) || !std::isfinite(options.acceleration))
    throw InputError("progressive encoder: the acceleration must be positive, got " + std::to_string(options.acceleration));
  running_.assign(size_t(functions), 0.0);
  coefficients_.assign(size_t(functions) * size_t(channels), 0.0);
  delta_.assign(size_t(channels), 0.0);
}

void ProgressiveEncoder::reset() {
  std::fill(running_.begin(), running_.end(), 0.0);
  std::fill(coefficients_.begin(), coefficients_.end(), 0.0);
  total_weight_ = 0;
}

void ProgressiveEncoder::add(const double* basis, const double* value, double weight) {
  const size_t C = size_t(channels_);
  total_weight_ += weight;
  const double s = weight / total_weight_;  // 1/k for unit weights
  for (size_t c = 0; c < C; ++c) delta_[c] = value[c];
  for (int i = 0; i < functions_; ++i)
    for (size_t c = 0; c < C; ++c) delta_[c] -= coefficients_[size_t(i) * C + c] * basis[i];
  for (int i = 0; i < functions_; ++i) {
    const size_t fi = size_t(i);
    const double B = basis[i];
    running_[fi] += (B * B - running_[fi]) * s;
    double I = running_[fi];
    if (options_.denominator == ProgressiveOptions::Denominator::Interpolated) I = s * start_[fi] + (1 - s) * running_[fi];
    else if (options_.denominator == ProgressiveOptions::Denominator::Clamped) I = std::max(I, mean_square_[fi]);
    if (B == 0.0 || !(I > 0)) continue;  // no information on this function from this sample
    const double scale = options_.acceleration * s * B / I;
    for (size_t c = 0; c < C; ++c) {
      double& b = coefficients_[fi * C + c];
      const double before = b;
      b += delta_[c] * scale;
      if (options_.non_negative && b < 0) b = 0;
      if (options_.gauss_seidel) delta_[c] -= (b - before) * B;
    }
  }
}

}  // namespace prtsub
