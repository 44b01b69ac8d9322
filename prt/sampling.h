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

//! Zaremba's index of the 2D lattice {(i/n1, {(i·s/n1 + k)/n2})} (its Hermite normal form; n2 = 1
//! is the rank-1 lattice {(q/n1, {q·s/n1})}): the least max(1,|h1|)·max(1,|h2|) over nonzero
//! dual vectors. The larger, the smaller the worst-case error for integrands of bounded
//! variation; Fibonacci lattices are the best rank-1 lattices in 2D.
uint64_t zaremba_index(uint64_t n1, uint64_t n2, uint64_t s);
//! The rank-1 lattice's {(q/M, {q·a/M})}.
inline uint64_t zaremba_index(uint32_t M, uint32_t a) { return zaremba_index(M, 1, a); }

//! A lattice of `base` points that doubles: lattice j has base·2^j points and lattice j + 1 is
//! lattice j and a copy of it moved by offsets[j]. Lattice 0 is rank-1, its generator the best by
//! Zaremba's index near base·(√5−1)/2 (a Fibonacci-like lattice). Three lattices contain lattice
//! j twice over: two rank-1 ones, and one whose elevation coordinate takes half as many values.
//! Each doubling takes the better rank-1 one by Zaremba's index, or the third where its index is
//! at least 1.5 times that. Up to 2026-12-07 only the rank-1 two were weighed, and after three
//! doublings of 64 points the index was a third of a fresh lattice's (BENCHMARKS.md, "Later
//! rounds on lattices that stay good").
struct DoublingLattice {
  struct Form {
    uint64_t n1 = 1, n2 = 1, s = 0;  //!< the Hermite normal form of zaremba_index
  };
  uint32_t base = 0, generator = 0;
  std::vector<Form> forms;               //!< lattice j
  std::vector<Eigen::Vector2d> offsets;  //!< lattice j + 1 = lattice j ∪ (lattice j + offsets[j])
};
DoublingLattice doubling_lattice(uint32_t base, int doublings);

//! Point n of the doubling sequence, unshifted, in [0,1)²: lattice 0's points (q/base,
//! {q·a/base}) for n < base, then each doubling's new points, point n − M_j of the sequence moved
//! by offsets[j] for M_j ≤ n < 2·M_j. Its first base·2^j points are lattice j, so a later round
//! of rays that continues from n = base·2^j fills in the earlier strata.
//! \param l doubling_lattice(base, d) with base·2^d > n
Eigen::Vector2d doubling_lattice_point(uint32_t n, const DoublingLattice& l);

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
LatticeTable lattice_table(uint32_t first, uint32_t count, const DoublingLattice& l);

}  // namespace prtsub
