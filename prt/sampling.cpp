#include "prtsub/prt/sampling.h"

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace prtsub {

void tangent_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

uint64_t zaremba_index(uint64_t n1, uint64_t n2, uint64_t s) {
  if (n1 * n2 <= 1) return 1;
  // Dual vectors: h2 = n2·t and h1 ≡ −t·s (mod n1); t = 0 leaves (n1, 0).
  uint64_t best = n1;
  for (uint64_t t = 1; n2 * t < best; ++t) {
    uint64_t h1 = (n1 - (t * s) % n1) % n1;
    h1 = std::min(h1, n1 - h1);
    best = std::min(best, std::max<uint64_t>(1, h1) * n2 * t);
  }
  return best;
}

namespace {
// The lattice that is not rank-1 stratifies the elevation (x) half as finely: its x takes n1 =
// M/2 values where a rank-1 lattice's takes M. It is taken only where its index is this much
// larger (bench/adaptive_lattice.sh: at 1.28× it cost bunny's transfer 7% more variance, at 3.2×
// it took a quarter off bunny's and armadillo's).
constexpr double kRank2Gain = 1.5;
}  // namespace

DoublingLattice doubling_lattice(uint32_t base, int doublings) {
  DoublingLattice l;
  l.base = base;
  if (base == 0) return l;
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
  l.generator = best;
  l.forms.push_back({base, 1, best % base});
  // The lattices holding lattice (n1, n2, s) twice over: (2n1, n2, s) and (2n1, n2, s + n1),
  // each adding (1/2n1, s'/2n1n2), and (n1, 2n2, 2s mod n1), adding (0, 1/2n2).
  for (int j = 1; j <= doublings && uint64_t(base) << j <= (uint64_t(1) << 31); ++j) {
    const DoublingLattice::Form f = l.forms.back();
    const DoublingLattice::Form options[3] = {{2 * f.n1, f.n2, f.s}, {2 * f.n1, f.n2, f.s + f.n1}, {f.n1, 2 * f.n2, (2 * f.s) % f.n1}};
    uint64_t z[3];
    for (int k = 0; k < 3; ++k) z[k] = zaremba_index(options[k].n1, options[k].n2, options[k].s);
    int pick = z[1] > z[0] ? 1 : 0;
    if (double(z[2]) >= kRank2Gain * double(z[pick])) pick = 2;
    const DoublingLattice::Form& g = options[pick];
    l.forms.push_back(g);
    l.offsets.push_back(pick < 2 ? Eigen::Vector2d(0.5 / double(f.n1), double(g.s) / (2.0 * double(f.n1) * double(f.n2)))
                                 : Eigen::Vector2d(0.0, 0.5 / double(f.n2)));
  }
  return l;
}

Eigen::Vector2d doubling_lattice_point(uint32_t n, const DoublingLattice& l) {
  if (l.base == 0) throw std::out_of_range("doubling_lattice_point: an empty lattice");
  // n's binary digits above the base, from the top: each set one is a doubling's offset.
  Eigen::Vector2d moved(0, 0);
  uint64_t m = n;
  for (size_t j = l.offsets.size(); j-- > 0;)
    if (m >= uint64_t(l.base) << j) moved += l.offsets[j], m -= uint64_t(l.base) << j;
  if (m >= l.base) throw std::out_of_range("doubling_lattice_point: point beyond the lattice's doublings");
  const uint64_t g = l.generator;
  Eigen::Vector2d p(double(m) / double(l.base) + moved.x(), double((m * g) % l.base) / double(l.base) + moved.y());
  return p - p.array().floor().matrix();  // no half-cell offset: it would not nest
}

LatticeTable lattice_table(uint32_t first, uint32_t count, const DoublingLattice& l) {
  LatticeTable t;
  t.u.reserve(count), t.cos_v.reserve(count), t.sin_v.reserve(count);
  for (uint32_t k = 0; k < count; ++k) t.push_back(doubling_lattice_point(first + k, l));
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
