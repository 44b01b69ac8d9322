// Deterministic direction sampling for transfer: a cosine-weighted Fibonacci lattice
// per point, decorrelated between points by a seeded random shift.
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace prtsub {

//! SplitMix64 finaliser: a well-mixed 64-bit hash.
inline uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

//! A uniform double in [0, 1) from 53 bits of a hash.
inline double to_unit(uint64_t h) { return double(h >> 11) * (1.0 / 9007199254740992.0); }

//! Small counter-based generator: the stream is a function of (seed, stream id) only.
class Rng {
 public:
  Rng(uint64_t seed, uint64_t stream) : state_(mix64(seed ^ mix64(stream + 0x632BE59BD9B4E019ull))) {}
  uint64_t next() { return mix64(state_++); }
  double uniform() { return to_unit(next()); }

 private:
  uint64_t state_;
};

//! Right-handed orthonormal frame (t, b, n) for unit n, continuous except at n.z = -1
//! (Duff et al. 2017).
void tangent_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b);

//! Cosine-weighted direction i of `count` in the local frame (z = normal), from a Fibonacci
//! lattice shifted toroidally by (shift_u, shift_v). Every direction is individually
//! cosine-distributed when the shift is uniform, so estimators built on it are unbiased.
Eigen::Vector3d lattice_cosine_direction(uint32_t i, uint32_t count, double shift_u, double shift_v);

}  // namespace prtsub
