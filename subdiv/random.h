// Counter-based random numbers: every stream is a function of (seed, stream id), so results
// never depend on which thread draws them. Shared by every room (sampling, tests, refinement).
#pragma once

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

}  // namespace prtsub
