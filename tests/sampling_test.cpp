#include "prtsub/prt/sampling.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "helpers.h"

namespace prtsub {
namespace {

TEST(Sampling, TangentFrameIsRightHandedOrthonormalEverywhere) {
  std::vector<Eigen::Vector3d> normals = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, -1e-12, -1}};
  for (uint64_t s = 0; s < 100; ++s) normals.push_back(test::random_direction(s));
  for (auto n : normals) {
    n.normalize();
    Eigen::Vector3d t, b;
    tangent_frame(n, t, b);
    EXPECT_NEAR(t.norm(), 1, 1e-12);
    EXPECT_NEAR(b.norm(), 1, 1e-12);
    EXPECT_NEAR(t.dot(b), 0, 1e-12);
    EXPECT_NEAR(t.dot(n), 0, 1e-12);
    EXPECT_NEAR(t.cross(b).dot(n), 1, 1e-12);
  }
}

// Zaremba's index by brute force over a box of dual vectors, independent of the library's scan.
uint64_t zaremba_brute(int64_t M, int64_t a) {
  uint64_t best = uint64_t(M);
  for (int64_t h1 = -M; h1 <= M; ++h1)
    for (int64_t h2 = -M; h2 <= M; ++h2) {
      if ((h1 == 0 && h2 == 0) || ((h1 + a * h2) % M + M) % M != 0) continue;
      best = std::min(best, uint64_t(std::max<int64_t>(1, std::abs(h1)) * std::max<int64_t>(1, std::abs(h2))));
    }
  return best;
}

TEST(Sampling, ZarembaIndexMatchesABruteForceSearch) {
  for (auto [M, a] : {std::pair<int, int>{89, 55}, {128, 79}, {128, 64}, {100, 3}, {64, 1}, {55, 34}, {256, 207}})
    EXPECT_EQ(zaremba_index(uint32_t(M), uint32_t(a)), zaremba_brute(M, a)) << M << " " << a;
  // The Fibonacci lattice of 89 points is among the best there are: no generator does better.
  uint64_t best = 0;
  for (uint32_t a = 1; a < 89; ++a) best = std::max(best, zaremba_index(89, a));
  EXPECT_EQ(zaremba_index(89, 55), best);
}

TEST(Sampling, EachDoubledLatticeContainsTheOneBefore) {
  for (uint32_t base : {128u, 100u, 7u}) {
    const std::vector<uint32_t> a = doubling_generators(base, 4);
    ASSERT_EQ(a.size(), 5u);
    // The base is a good lattice: at least as good by Zaremba's index as round(base·golden).
    EXPECT_GE(zaremba_index(base, a[0]), zaremba_index(base, uint32_t(std::lround(0.6180339887 * base)))) << base;
    uint64_t M = base;
    for (size_t j = 1; j < a.size(); ++j, M *= 2) EXPECT_EQ(a[j] % M, a[j - 1] % M) << base << " " << j;
    // The first base·2^j points of the sequence are lattice j, each point once.
    for (size_t j = 0; j < a.size(); ++j) {
      const uint64_t Mj = uint64_t(base) << j;
      std::vector<int> hit(Mj, 0);
      for (uint32_t n = 0; n < Mj; ++n) {
        const Eigen::Vector2d q = doubling_lattice_point(n, base, a);
        const auto k = static_cast<uint64_t>(std::llround(q.x() * double(Mj)));
        ASSERT_LT(k, Mj);
        ++hit[k];
        // On the lattice: (k, k·a_j)/M_j, to rounding.
        EXPECT_NEAR(q.x() * double(Mj), double(k), 1e-9);
        EXPECT_NEAR(q.y(), double((k * a[j]) % Mj) / double(Mj), 1e-12);
      }
      EXPECT_EQ(*std::min_element(hit.begin(), hit.end()), 1) << base << " " << j;
      EXPECT_EQ(*std::max_element(hit.begin(), hit.end()), 1) << base << " " << j;
    }
  }
}

TEST(Sampling, ShiftedLatticeDirectionsAreCosineDistributed) {
  // Under pdf cos/π: E[cos θ] = 2/3 and E[cos² θ] = 1/2, E[x] = E[y] = 0. cos²θ = 1 − u is
  // linear in the lattice's stratified coordinate, so a shifted lattice of n points misses its
  // mean by at most 1/(2n) (1.2e-4 here); Monte Carlo would miss by ~1/sqrt(n) = 1.6e-2.
  const uint32_t n = 4096;
  const std::vector<uint32_t> a = doubling_generators(n, 0);
  double m1 = 0, m2 = 0, mx = 0, my = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector2d q = doubling_lattice_point(i, n, a);
    const double u = q.x() + 0.37, v = q.y() + 0.81;
    const Eigen::Vector3d d = cosine_direction(u - std::floor(u), v - std::floor(v));
    EXPECT_NEAR(d.norm(), 1, 1e-12);
    EXPECT_GE(d.z(), 0);
    m1 += d.z(), m2 += d.z() * d.z(), mx += d.x(), my += d.y();
  }
  EXPECT_NEAR(m1 / n, 2.0 / 3.0, 1.0 / n);
  EXPECT_NEAR(m2 / n, 0.5, 0.5 / n + 1e-12);
  EXPECT_NEAR(mx / n, 0, 1e-3);
  EXPECT_NEAR(my / n, 0, 1e-3);
}

TEST(Sampling, ATabulatedLatticeGivesTheShiftedPointsDirectionsUpToRounding) {
  // The table (cos and sin of each point's azimuth, turned by the shift's angle) against the
  // shifted point's direction computed directly, for both warps, a doubled lattice read from an
  // offset (a later round), and shifts that wrap u and v past 1.
  const uint32_t base = 48;
  const std::vector<uint32_t> a = doubling_generators(base, 2);
  const LatticeTable table = lattice_table(base, 3 * base, base, a);
  ASSERT_EQ(table.size(), size_t(3 * base));
  Rng rng(3, 1);
  for (int copy = 0; copy < 20; ++copy) {
    const double s = rng.uniform(), t = rng.uniform();
    const LatticeShift shift(s, t);
    for (uint32_t k = 0; k < table.size(); ++k) {
      const Eigen::Vector2d q = doubling_lattice_point(base + k, base, a);
      EXPECT_EQ(table.u[k], q.x());
      const double u = q.x() + s, v = q.y() + t;
      const Eigen::Vector3d want = cosine_direction(u - std::floor(u), v - std::floor(v));
      const Eigen::Vector3d want_uniform = uniform_hemisphere_direction(u - std::floor(u), v - std::floor(v));
      EXPECT_LT((shifted_direction(table, k, shift) - want).cwiseAbs().maxCoeff(), 1e-13) << k;
      EXPECT_LT((shifted_direction(table, k, shift, true) - want_uniform).cwiseAbs().maxCoeff(), 1e-13) << k;
    }
  }
}

TEST(Sampling, RngStreamsDependOnlyOnSeedAndStream) {
  Rng a(5, 9), b(5, 9), c(5, 10), d(6, 9);
  double va = a.uniform();
  EXPECT_EQ(va, b.uniform());
  EXPECT_NE(va, c.uniform());
  EXPECT_NE(va, d.uniform());
  // Uniformity: mean of many draws near 1/2 within 5 standard errors.
  Rng r(1, 1);
  double sum = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) sum += r.uniform();
  EXPECT_NEAR(sum / n, 0.5, 5 * std::sqrt(1.0 / 12 / n));
}

}  // namespace
}  // namespace prtsub
