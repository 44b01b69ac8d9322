// Spherical-Gaussian lobes: a fixed, non-negative basis for transfer, and lights projected onto it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "prtsub/prt/lights.h"
#include "prtsub/subdiv/mesh.h"

namespace prtsub {

//! N lobes G_k(ω) = exp(λ (μ_k·ω − 1)), peak 1 at their axis μ_k, all of one sharpness λ.
//! The set is fixed by N alone (docs/transfer.md, "Spherical-Gaussian lobes"): axes on the
//! spherical Fibonacci lattice, μ_k = (√(1−z²) cos φ_k, √(1−z²) sin φ_k, z), z = 1 − (2k+1)/N,
//! φ_k = k·π(3 − √5); λ = ln 2 / (1 − cos(θ/2)) with θ = √(4π/N) the mean spacing of the axes, so
//! that a lobe falls to half its peak halfway to its neighbours (λ ≈ 4.089 for 9 lobes, 5.412 for 12).
struct SgBasis {
  std::vector<Eigen::Vector3d> axes;
  double sharpness = 0;
  int size() const { return static_cast<int>(axes.size()); }
};

constexpr int kMinSgLobes = 4, kMaxSgLobes = 64;
//! The most lobes an asset takes: past 16, order-10 SH (kMaxShOrder, which every consumer relights
//! through) no longer carries a lobe's light to 0.2% (sg_shading_order).
constexpr int kMaxSgAssetLobes = 16;

//! \throw InputError unless kMinSgLobes ≤ lobes ≤ kMaxSgLobes
SgBasis sg_basis(int lobes);

//! The SH order an SG asset is relit through (sg_to_sh at it, exact for every light of that order):
//! the lowest whose bands hold a lobe's RMS to within 0.1% (Σ_{l≥L} (2l+1) g_l² ≤ 10⁻⁶ Σ_l (2l+1) g_l²),
//! at most kMaxShOrder. What a light holds above it reaches the lobes at most that much: 8 for 9
//! lobes, 10 for 12, and 10 for 16 (whose bands above hold 0.15%).
int sg_shading_order(const SgBasis& basis);

//! Whether a sharpness a file records is this set's (to 1e-9 of it): a reader relights with its
//! own lobes, so a file of other lobes must be refused.
bool sg_sharpness_matches(const SgBasis& basis, double sharpness);

//! Every lobe's value at unit direction w (out: size() values).
void sg_eval(const SgBasis& basis, const Eigen::Vector3d& w, double* out);

//! ∫ G_i G_j dω in closed form: 4π e^{−2λ} sinh(r)/r, r = λ‖μ_i + μ_j‖ (4π e^{−2λ} when r = 0).
Eigen::MatrixXd sg_gram(const SgBasis& basis);

//! g_l = ∫ P_l(μ·ω) e^{λ(μ·ω − 1)} dω = 4π e^{−λ} i_l(λ) (i_l the modified spherical Bessel function
//! of the first kind), l = 0 .. order−1: by Funk–Hecke, ∫ y_lm(ω) G(ω) dω = g_l y_lm(μ).
//! \throw InputError unless λ > 0 and finite, 1 ≤ order ≤ 64
std::vector<double> sg_zonal(double sharpness, int order);

//! What each lobe sees of a light: L_k = ∫ L(ω) G_k(ω) dω per channel, #N by 3. For an SH light
//! in closed form, L_k = Σ_lm g_l y_lm(μ_k) l_lm, exact at the light's order. A transfer
//! T(ω) = Σ_k c_k G_k(ω) then shades as radiance = albedo/π · Σ_k c_k L_k.
Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> sg_light(const SgBasis& basis, const ShLight& light);

//! Lobe coefficients (#P by N, one row per point) as SH transfer of `order` (#P by order²): by
//! Funk–Hecke, Σ_k c_k G_k projects onto y_lm as Σ_k c_k g_l y_lm(μ_k). Exact for every light of
//! that order (Σ_i l_i t_i = Σ_k c_k L_k), so eval's metric judges lobes as it judges SH.
//! \throw InputError unless coefficients has N columns and 1 ≤ order ≤ kMaxShOrder
RowMatrixXd sg_to_sh(const SgBasis& basis, const RowMatrixXd& coefficients, int order);

//! The same for a lat-long radiance map (the layout of environment_light), integrated texel by
//! texel with the same exact solid angles.
//! \throw InputError as environment_light does
Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> sg_light(const SgBasis& basis, const Image& latlong);

}  // namespace prtsub
