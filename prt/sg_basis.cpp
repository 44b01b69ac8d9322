// Spherical-Gaussian lobes for transfer (issue 15, point 3), the groundwork: the fixed lobe set,
// its Gram matrix, and lights projected onto it.
//
// SH transfer relights by a dot product because SH are orthonormal: Σ l_i t_i = ∫ L T. Lobes are
// not orthogonal, so the coefficients c_k of T ≈ Σ c_k G_k come from a least-squares fit (the
// progressive encoder, progressive_encoder.h, which also keeps them non-negative), and the light
// is not expanded in the lobes but integrated against them: ∫ L T ≈ Σ_k c_k ∫ L G_k = Σ c_k L_k.
// Each lobe is zonal about its axis, so by the Funk–Hecke theorem an SH light projects onto it
// band by band: ∫ y_lm G_k = g_l y_lm(μ_k), g_l = 2π ∫ P_l(t) e^{λ(t−1)} dt = 4π e^{−λ} i_l(λ).
// The modified spherical Bessel function comes from its power series,
//     i_l(x) = Σ_k x^{l+2k} / (2^k k! (2l+2k+1)!!),
// all terms positive (no cancellation) and converging for any x; at the sharpnesses a lobe set
// uses (λ of a few to tens) a few dozen terms reach double precision.
#include "prtsub/prt/sg_basis.h"

#include <cmath>
#include <string>

#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

SgBasis sg_basis(int lobes) {
  if (lobes < kMinSgLobes || lobes > kMaxSgLobes)
    throw InputError("spherical Gaussians: between " + std::to_string(kMinSgLobes) + " and " + std::to_string(kMaxSgLobes) +
                     " lobes, got " + std::to_string(lobes));
  SgBasis b;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int k = 0; k < lobes; ++k) {
    const double z = 1 - (2.0 * k + 1) / lobes, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = golden * k;
    b.axes.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  const double spacing = std::sqrt(4 * M_PI / lobes);
  b.sharpness = std::log(2.0) / (1 - std::cos(spacing / 2));
  return b;
}

int sg_shading_order(const SgBasis& basis) {
  constexpr int kBands = 64;
  const std::vector<double> g = sg_zonal(basis.sharpness, kBands);
  double total = 0;
  for (int l = 0; l < kBands; ++l) total += (2 * l + 1) * g[size_t(l)] * g[size_t(l)];
  double rest = total;
  for (int L = 1; L <= kMaxShOrder; ++L) {
    rest -= (2 * L - 1) * g[size_t(L - 1)] * g[size_t(L - 1)];
    if (rest <= 1e-6 * total) return L;
  }
  return kMaxShOrder;
}

bool sg_sharpness_matches(const SgBasis& basis, double sharpness) { return std::abs(sharpness - basis.sharpness) <= 1e-9 * basis.sharpness; }

void sg_eval(const SgBasis& basis, const Eigen::Vector3d& w, double* out) {
  for (int k = 0; k < basis.size(); ++k) out[k] = std::exp(basis.sharpness * (basis.axes[size_t(k)].dot(w) - 1));
}

Eigen::MatrixXd sg_gram(const SgBasis& basis) {
  const int N = basis.size();
  const double l = basis.sharpness, e = 4 * M_PI * std::exp(-2 * l);
  Eigen::MatrixXd G(N, N);
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) {
      const double r = l * (basis.axes[size_t(i)] + basis.axes[size_t(j)]).norm();
      // sinh(r)/r e^{−2λ} without overflow for sharp lobes: (e^{r−2λ} − e^{−r−2λ}) / 2r.
      G(i, j) = r < 1e-8 ? e : 4 * M_PI * (std::exp(r - 2 * l) - std::exp(-r - 2 * l)) / (2 * r);
    }
  return G;
}

std::vector<double> sg_zonal(double sharpness, int order) {
  if (!(sharpness > 0) || !std::isfinite(sharpness) || order < 1 || order > 64)
    throw InputError("spherical Gaussians: the sharpness must be positive and the order 1 to 64");
  const double x = sharpness;
  std::vector<double> g(static_cast<size_t>(order));
  double lead = 1;  // x^l / (2l+1)!!, times e^{−x} folded in at the start to keep it finite
  for (int l = 0; l < order; ++l) {
    if (l > 0) lead *= x / (2 * l + 1);
    double term = std::exp(-x) * lead, sum = 0;
    for (int k = 0; k < 100000 && term > 1e-18 * sum; ++k) {
      sum += term;
      term *= x * x / (2.0 * (k + 1) * (2 * l + 2 * k + 3));
    }
    g[size_t(l)] = 4 * M_PI * sum;
  }
  return g;
}

Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> sg_light(const SgBasis& basis, const ShLight& light) {
  const int K = sh_count(light.order);
  if (light.order < 1 || light.coeffs.rows() != K) throw InputError("spherical Gaussians: the SH light's coefficients do not match its order");
  const std::vector<double> g = sg_zonal(basis.sharpness, light.order);
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> out(basis.size(), 3);
  std::vector<double> y(static_cast<size_t>(K));
  for (int k = 0; k < basis.size(); ++k) {
    const Eigen::Vector3d& a = basis.axes[size_t(k)];
    sh_eval(light.order, a.x(), a.y(), a.z(), y.data());
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (int l = 0; l < light.order; ++l)
      for (int m = -l; m <= l; ++m) sum += g[size_t(l)] * y[size_t(sh_index(l, m))] * light.coeffs.row(sh_index(l, m));
    out.row(k) = sum;
  }
  return out;
}

RowMatrixXd sg_to_sh(const SgBasis& basis, const RowMatrixXd& coefficients, int order) {
  if (coefficients.cols() != basis.size()) throw InputError("spherical Gaussians: one coefficient per lobe expected");
  if (order < 1 || order > kMaxShOrder) throw InputError("SH order must be between 1 and " + std::to_string(kMaxShOrder));
  const int N = basis.size(), K = sh_count(order);
  const std::vector<double> g = sg_zonal(basis.sharpness, order);
  RowMatrixXd M(N, K);  // row k: lobe k's SH projection, g_l y_lm(μ_k)
  for (int k = 0; k < N; ++k) {
    const Eigen::Vector3d& a = basis.axes[size_t(k)];
    sh_eval(order, a.x(), a.y(), a.z(), M.row(k).data());
    for (int l = 0; l < order; ++l) M.row(k).segment(l * l, 2 * l + 1) *= g[size_t(l)];
  }
  return coefficients * M;
}

Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> sg_light(const SgBasis& basis, const Image& img) {
  return integrate_latlong(img, basis.size(), [&basis](const Eigen::Vector3d& d, double* g) { sg_eval(basis, d, g); });
}

}  // namespace prtsub
