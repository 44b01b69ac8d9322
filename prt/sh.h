// Real orthonormal spherical harmonics, orders 1 to 10 (order = number of bands, N² coefficients).
//
// Convention (docs/sh_convention.md is the contract): index i = l(l+1)+m; evaluated on the
// mesh's own axes with no swap and no Condon-Shortley phase, so y_{1,-1} = c·y, y_{1,0} = c·z,
// y_{1,1} = c·x with c = sqrt(3/(4π)) > 0.
#pragma once

#include <Eigen/Core>

namespace prtsub {

//! Channels of a transfer matrix with `cols` columns: 1 for N², 3 for 3·N² (RGB transfer, the
//! red, green and blue blocks side by side), else 0 (N from 1 to kMaxShOrder).
int transfer_channels(Eigen::Index cols);

constexpr int kMaxShOrder = 10;

constexpr int sh_count(int order) { return order * order; }
constexpr int sh_index(int l, int m) { return l * (l + 1) + m; }

//! Evaluates all order² basis functions at the unit direction (x, y, z).
//! \pre 1 <= order <= kMaxShOrder, x²+y²+z² = 1; out has room for order² values.
void sh_eval(int order, double x, double y, double z, double* out);

//! Convenience form returning a vector of order² values.
Eigen::VectorXd sh_eval(int order, const Eigen::Vector3d& direction);

//! Â_l: the clamped cosine max(n·ω, 0) projects to coefficients Â_l · y_lm(n).
//! Â_0 = π, Â_1 = 2π/3, Â_2 = π/4, odd l > 1 give 0.
double clamped_cosine_band(int l);

//! Unshadowed diffuse transfer ∫ max(n·ω,0) y_i(ω) dω for unit normal n, in closed form.
void unshadowed_transfer(int order, const Eigen::Vector3d& n, double* out);
Eigen::VectorXd unshadowed_transfer(int order, const Eigen::Vector3d& n);

}  // namespace prtsub
