// Deterministic direction sampling for transfer: cosine-weighted rank-1 lattices that can be
// doubled, per point, decorrelated between points by a seeded random shift.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "prtsub/subdiv/random.h"

namespace prtsub {

//! Right-handed orthonormal frame (t, b, n) for unit n, continuous except at n.z = -1
//! (Duff et al. 2017).
void tangent_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b);

//! Zaremba's index of the 2D rank-1 lattice {(q/M, q·a/M)}: the least max(1,|h1|)·max(1,|h2|)
//! over nonzero dual vectors (h1 + a·h2 ≡ 0 mod M). The larger, the smaller the worst-case
//! error for integrands of bounded variation; Fibonacci lattices are the best in 2D.
uint64_t zaremba_index(uint32_t M, uint32_t a);

//! A lattice of `base` points that can be doubled `doublings` times: generators a_0 .. a_d,
//! lattice j having M_j = base·2^j points (q/M_j, {q·a_j/M_j}). a_0 is the best by Zaremba's
//! index near base·(√5−1)/2 (a Fibonacci-like lattice), and each a_j is a_{j−1} or a_{j−1} + M_{j−1},
//! the two that contain lattice j−1, whichever has the larger index.
std::vector<uint32_t> doubling_generators(uint32_t base, int doublings);

//! Point n of the doubling sequence, unshifted, in [0,1)²: the base lattice's points for
//! n < base, then each doubling's new points (odd q). Its first base·2^j points are lattice j,
//! so a later round of rays that continues from n = base·2^j fills in the earlier strata.
//! \param a doubling_generators(base, d) with base·2^d > n
Eigen::Vector2d doubling_lattice_point(uint32_t n, uint32_t base, const std::vector<uint32_t>& a);

//! The cosine-weighted direction for (u, v) ∈ [0,1)² in the local frame (z = normal), by
//! Malley's method: uniform on the disk (area-preserving in u), lifted to the hemisphere. Every
//! direction is individually cosine-distributed when (u, v) is uniform (a random shift of a
//! lattice), so estimators built on it are unbiased.
Eigen::Vector3d cosine_direction(double u, double v);

//! The uniformly distributed direction on the hemisphere (z = normal) for (u, v) ∈ [0,1)²:
//! z = 1 − u (equal solid angle per unit of u), azimuth 2πv.
Eigen::Vector3d uniform_hemisphere_direction(double u, double v);

//! Lattice points tabulated for directions: a tracing call gives every point the same lattice
//! points, each point's copy shifted by its own (s, t). Each point (u, v) is kept as u and its
//! azimuth's cos 2πv and sin 2πv, so a shifted copy costs no lattice arithmetic and no
//! trigonometry per ray: the shift's t turns the azimuth by angle addition (the wrap of v + t
//! into [0,1) changes nothing there), and u moves to {u + s}.
struct LatticeTable {
  std::vector<double> u, cos_v, sin_v;
  void push_back(const Eigen::Vector2d& uv) {
    u.push_back(uv.x()), cos_v.push_back(std::cos(2 * M_PI * uv.y())), sin_v.push_back(std::sin(2 * M_PI * uv.y()));
  }
  size_t size() const { return u.size(); }
};

//! A copy's shift (s, t) ∈ [0,1)², its turn cos 2πt and sin 2πt computed once.
struct LatticeShift {
  double s = 0, turn_cos = 1, turn_sin = 0;
  LatticeShift() = default;
  LatticeShift(double s_, double t) : s(s_), turn_cos(std::cos(2 * M_PI * t)), turn_sin(std::sin(2 * M_PI * t)) {}
};

//! cosine_direction({u_k + s}, {v_k + t}) (or uniform_hemisphere_direction's), equal to it up to
//! rounding.
inline Eigen::Vector3d shifted_direction(const LatticeTable& table, size_t k, const LatticeShift& shift, bool uniform = false) {
  double u = table.u[k] + shift.s;
  u -= std::floor(u);
  const double c = table.cos_v[k] * shift.turn_cos - table.sin_v[k] * shift.turn_sin;
  const double sn = table.sin_v[k] * shift.turn_cos + table.cos_v[k] * shift.turn_sin;
  const double z = uniform ? 1 - u : std::sqrt(std::max(0.0, 1 - u));
  const double r = uniform ? std::sqrt(std::max(0.0, 1 - z * z)) : std::sqrt(u);
  return Eigen::Vector3d(r * c, r * sn, z);
}

//! Points first .. first + count − 1 of the doubling sequence (doubling_lattice_point), tabulated.
LatticeTable lattice_table(uint32_t first, uint32_t count, uint32_t base, const std::vector<uint32_t>& a);

}  // namespace prtsub
