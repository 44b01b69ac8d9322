#include "prtsub/prt/vertex_top_up.h"

#include <gtest/gtest.h>

#include <cmath>

#include "helpers.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

int rays_at(int level) { return level < 0 ? 0 : int(std::lround(16 * std::exp2(level / 4.0))); }

// Every vertex after R rays, each to at most 17R in all, counted equally.
TopUpPlan plan(const std::vector<double>& v, int R, uint64_t budget, const std::vector<double>& weight = {}) {
  return plan_top_up(v, std::vector<double>(v.size(), R), budget, weight, 17.0 * R);
}

TEST(TopUp, WaterFillingGivesOpenVerticesNothingAndTheNoisiestTheMost) {
  // Per-ray variances c = R·v; the optimum is R + e = λ√c where that exceeds R.
  const int R = 64;
  const std::vector<double> v = {0, 0, 1e-6, 0.01, 0.04, 0.16, 0.64, 2.56, INFINITY, NAN};
  const uint64_t budget = 700;  // λ ≈ 40: the three noisiest get rays, none reaches the cap
  const TopUpPlan p = plan(v, R, budget);
  ASSERT_EQ(p.level.size(), v.size());
  EXPECT_EQ(p.level[0], -1);  // exact: nothing to gain
  EXPECT_EQ(p.level[1], -1);
  EXPECT_EQ(p.level[8], -1);  // unknown variances are not guessed at
  EXPECT_EQ(p.level[9], -1);
  EXPECT_EQ(p.level[2], -1);  // far below the water line
  for (size_t i = 3; i + 1 < 8; ++i) EXPECT_LE(p.level[i], p.level[i + 1]) << i;
  uint64_t total = 0;
  for (int l : p.level) total += uint64_t(rays_at(l));
  EXPECT_EQ(total, p.rays);
  EXPECT_GT(double(total), 0.8 * budget);  // rounding to 2^(1/4) steps moves each count by at most 9%
  EXPECT_LT(double(total), 1.2 * budget);
  // The optimum's shape: where both get rays, R + e grows as √c, so each 4× in variance doubles
  // R + e (to the rounding of the levels, 2^(1/8) each way).
  EXPECT_EQ(p.level[4], -1);
  ASSERT_GE(p.level[5], 0);
  for (size_t i = 6; i < 8; ++i) {
    const double ratio = double(R + rays_at(p.level[i])) / double(R + rays_at(p.level[i - 1]));
    EXPECT_NEAR(std::log2(ratio), 1.0, 0.3) << i;
  }
  // Weights (the area a vertex interpolates over) count like variance: 4× the weight at equal
  // variance doubles R + e, and a weight of 0 gets nothing.
  const TopUpPlan weighted = plan({0.1, 0.1, 0.1}, R, 600, {1.0, 4.0, 0.0});
  ASSERT_GE(weighted.level[0], 0);
  EXPECT_NEAR(std::log2(double(R + rays_at(weighted.level[1])) / double(R + rays_at(weighted.level[0]))), 1.0, 0.3);
  EXPECT_EQ(weighted.level[2], -1);
  EXPECT_THROW(plan(v, R, budget, {1.0}), InputError);
  EXPECT_EQ(plan(v, R, 0).vertices, 0u);   // no budget
  EXPECT_EQ(plan(v, 1, budget).vertices, 0u);  // one ray: no variance to go by
  // At most 16× the first round each, however large the budget.
  for (int l : plan(v, R, 1000000000).level) EXPECT_LE(rays_at(l), int(16 * R * 1.1));
}

TEST(TopUp, MoreRaysWhereTheyCountAndTheSameForAnyThreadCount) {
  // A ground grid under a half-plane: vertices in the open see the whole sky (exact), those
  // under the edge are noisy. The second round must lower the summed error against a
  // high-ray reference, spend nothing in the open, and not depend on threads.
  const Mesh ground = test::build(test::grid(10, 0.3));
  const Mesh world = test::build(test::merge(test::grid(10, 0.3), test::quad(50, 0.2, false, 0.6)));
  const RayScene scene(world.positions, position_triangles(world));
  const RowMatrixX3d offsets = vertex_offset_directions(ground);
  TransferOptions o;
  o.rays = 32;
  std::vector<double> variance;
  const RowMatrixXd first = shadowed_transfer(scene, vertex_positions(ground), ground.normals, o, nullptr, {}, &offsets, &variance);
  TransferOptions ref = o;
  ref.rays = 16384, ref.seed = 77;
  const RowMatrixXd truth = shadowed_transfer(scene, vertex_positions(ground), ground.normals, ref, nullptr, {}, &offsets);
  const TopUpPlan p = plan(variance, o.rays, 32 * ground.num_vertices());
  for (size_t i = 0; i < variance.size(); ++i)
    if (variance[i] == 0) {
      EXPECT_EQ(p.level[i], -1) << i;
    }
  EXPECT_GT(p.vertices, 0u);
  RowMatrixXd x1 = first, x2 = first;
  std::vector<double> v1 = variance, v2 = variance;
  TransferOptions one = o, two = o;
  one.threads = 1, two.threads = 2;
  std::vector<double> r1(variance.size(), o.rays), r2 = r1;
  const TopUpStats s1 = apply_top_up(ground, scene, one, p, x1, v1, r1);
  apply_top_up(ground, scene, two, p, x2, v2, r2);
  EXPECT_EQ(r1, r2);
  // The planned variance is what the estimates then report, to within their own noise.
  EXPECT_NEAR(planned_variance(p, variance, std::vector<double>(variance.size(), o.rays), {}), s1.variance_after,
              0.3 * s1.variance_after);
  EXPECT_EQ(x1, x2);
  EXPECT_EQ(v1, v2);
  EXPECT_EQ(s1.rays, p.rays);
  EXPECT_LT(s1.variance_after, 0.7 * s1.variance_before);
  const double before = (first - truth).squaredNorm(), after = (x1 - truth).squaredNorm();
  // The expected squared errors are the summed variances; the measured ones follow them.
  EXPECT_LT(after, before);
  EXPECT_NEAR(after / before, s1.variance_after / s1.variance_before, 0.5 * s1.variance_after / s1.variance_before + 0.1);
  // Open vertices are untouched.
  for (size_t i = 0; i < variance.size(); ++i)
    if (variance[i] == 0) {
      EXPECT_EQ(x1.row(Eigen::Index(i)), first.row(Eigen::Index(i)));
    }
  std::vector<double> short_variance(3, 1.0);
  EXPECT_THROW(apply_top_up(ground, scene, o, p, x1, short_variance, r1), InputError);
}

}  // namespace
}  // namespace prtsub
