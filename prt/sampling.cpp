#include "prtsub/prt/sampling.h"

#include <cmath>
#include <numeric>
#include <vector>

namespace prtsub {

void tangent_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

uint64_t zaremba_index(uint32_t M, uint32_t a) {
  if (M <= 1) return 1;
  uint64_t best = M;  // h = (M, 0)
  for (uint64_t h2 = 1; h2 < M && h2 < best; ++h2) {
    uint64_t h1 = (M - (uint64_t(a) * h2) % M) % M;
    h1 = std::min(h1, M - h1);
    best = std::min(best, std::max<uint64_t>(1, h1) * h2);
  }
  return best;
}

std::vector<uint32_t> doubling_generators(uint32_t base, int doublings) {
  std::vector<uint32_t> a;
  if (base == 0) return a;
  // The base: the best index within a window around the golden section (every a when small).
  const double golden = 0.6180339887498948482 * base;
  const int64_t lo = base <= 64 ? 1 : std::max<int64_t>(1, std::llround(golden) - 24);
  const int64_t hi = base <= 64 ? int64_t(base) - 1 : std::min<int64_t>(int64_t(base) - 1, std::llround(golden) + 24);
  uint32_t best = 1 % std::max<uint32_t>(base, 1);
  uint64_t best_index = 0;
  for (int64_t c = lo; c <= hi; ++c) {
    const uint64_t z = zaremba_index(base, uint32_t(c));
    if (z > best_index || (z == best_index && std::abs(double(c) - golden) < std::abs(double(best) - golden)))
      best = uint32_t(c), best_index = z;
  }
  a.push_back(best);
  uint64_t M = base;
  for (int j = 1; j <= doublings && 2 * M <= (uint64_t(1) << 31); ++j) {
    const uint32_t keep = a.back(), moved = uint32_t(a.back() + M);
    M *= 2;
    a.push_back(zaremba_index(uint32_t(M), moved) > zaremba_index(uint32_t(M), keep) ? moved : keep);
  }
  return a;
}

Eigen::Vector2d doubling_lattice_point(uint32_t n, uint32_t base, const std::vector<uint32_t>& a) {
  uint64_t M = base, q = n;
  size_t j = 0;
  if (n >= base) {
    while (M <= n) M *= 2, ++j;
    q = 2 * (uint64_t(n) - M / 2) + 1;  // the odd points lattice j adds to lattice j − 1
  }
  const uint64_t g = a[std::min(j, a.size() - 1)];
  return {double(q) / double(M), double((q * g) % M) / double(M)};  // no half-cell offset: it would not nest
}

LatticeTable lattice_table(uint32_t first, uint32_t count, uint32_t base, const std::vector<uint32_t>& a) {
  LatticeTable t;
  t.u.reserve(count), t.cos_v.reserve(count), t.sin_v.reserve(count);
  for (uint32_t k = 0; k < count; ++k) t.push_back(doubling_lattice_point(first + k, base, a));
  return t;
}

Eigen::Vector3d cosine_direction(double u, double v) {
  const double r = std::sqrt(u), phi = 2.0 * M_PI * v;
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - u)));
}

}  // namespace prtsub

namespace prtsub {

Eigen::Vector3d uniform_hemisphere_direction(double u, double v) {
  const double z = 1.0 - u, r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = 2.0 * M_PI * v;
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
}

}  // namespace prtsub
