// Progressive least-squares encoding into any linear basis (Roughton 2020, paper 004).
#pragma once

#include <vector>

namespace prtsub {

struct ProgressiveOptions {
  //! The paper's acceleration factor α: each sample's correction is scaled by it. 1 is plain
  //! stochastic Jacobi/Gauss–Seidel; the paper finds 1–5 reasonable (faster, noisier).
  double acceleration = 1.0;
  //! Gauss–Seidel: the residual is updated after each function's correction, so overlapping
  //! functions do not all correct the same error. Jacobi (false): one residual for every function.
  bool gauss_seidel = true;
  //! Clamp each coefficient to ≥ 0 after every correction (the paper's non-negative encoding).
  //! Meant for bases of non-negative lobes (spherical Gaussians), not for SH.
  bool non_negative = false;
  //! The denominator ∫B_i² of each correction. Running: the running mean of B_i(ω_s)² alone,
  //! which early samples can make tiny. Interpolated (the paper's fix, section 3.1):
  //! s·start + (1 − s)·running mean, s = w_s / Σw (1/k for unit weights). Clamped: the running
  //! mean, but never below the true value.
  enum class Denominator { Running, Interpolated, Clamped } denominator = Denominator::Interpolated;
};

//! The state of one point's encoding: `functions` coefficients for each of `channels` values.
//! Feed samples with add(); the coefficients after any number of samples are the estimate.
//! Deterministic: the same samples in the same order give the same coefficients.
class ProgressiveEncoder {
 public:
  //! \param mean_square ∫B_i² under the sampling measure normalised to 1 (the Clamped floor)
  //! \param start each denominator's value before any sample (the Interpolated start): the
  //!        paper's 1 is the peak of its unit-height lobes, so give a bound on B_i²; for SH,
  //!        (2l+1)/4π by the addition theorem
  //! \throw InputError unless functions ≥ 1, channels ≥ 1, both arrays have `functions`
  //!        positive entries and the acceleration is positive
  ProgressiveEncoder(int functions, int channels, const ProgressiveOptions& options, std::vector<double> mean_square,
                     std::vector<double> start);

  //! Back to no samples (coefficients 0), keeping the basis and options.
  void reset();

  //! One sample: the basis functions' values at its direction (`functions` of them), its
  //! values (`channels`), and its weight (> 0; 1 for samples drawn from the sampling measure,
  //! else proportional to measure/pdf; only ratios of weights matter).
  void add(const double* basis, const double* value, double weight = 1.0);

  //! functions by channels, function-major: coefficient of function i, channel c at [i·C + c].
  const std::vector<double>& coefficients() const { return coefficients_; }
  double total_weight() const { return total_weight_; }
  int functions() const { return functions_; }
  int channels() const { return channels_; }

 private:
  int functions_, channels_;
  ProgressiveOptions options_;
  std::vector<double> mean_square_, start_, running_, coefficients_, delta_;
  double total_weight_ = 0;
};

}  // namespace prtsub
