// --order auto against closed forms: on a convex mesh nothing is blocked, so every vertex's
// transfer is the clamped cosine, whose band energies are known (A_l² (2l+1) / 4π), and the pilot
// must find exactly those truncations and no noise; a constant light needs one band; the noise
// falls as 1/√rays; and the choice is the same for any thread count.
#include "prtsub/prt/order_choice.h"

#include <gtest/gtest.h>

#include <cmath>

#include "helpers.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

struct Scene {
  Mesh mesh;
  RayScene rays;
  RowMatrixX3d points, offsets;
  explicit Scene(const RawMesh& raw)
      : mesh(test::build(raw)), rays(mesh.positions, position_triangles(mesh)), points(vertex_positions(mesh)),
        offsets(vertex_offset_directions(mesh)) {}
  OrderChoice choose(const TransferOptions& t, const OrderChoiceOptions& o) const {
    return choose_order(rays, points, mesh.normals, offsets, t, o);
  }
};

double band_energy(int l) { return clamped_cosine_band(l) * clamped_cosine_band(l) * (2 * l + 1) / (4 * M_PI); }

TEST(OrderChoice, AConvexMeshHasTheClampedCosinesTruncationAndNoNoise) {
  const Scene s(test::icosphere(2));
  TransferOptions t;
  t.rays = 64;
  OrderChoiceOptions o;
  o.max_order = 8;
  const OrderChoice c = s.choose(t, o);
  double unit2 = 0;
  for (int l = 0; l < 8; ++l) unit2 += band_energy(l);
  for (int N = 1; N <= 8; ++N) {
    double tail = 0;
    for (int l = N; l < 8; ++l) tail += band_energy(l);
    EXPECT_NEAR(c.truncation_percent[static_cast<size_t>(N - 1)], 100 * std::sqrt(tail / unit2), 1e-9) << N;
    EXPECT_EQ(c.noise_percent[static_cast<size_t>(N - 1)], 0.0) << N;
  }
  // No noise to hide below: only an order that leaves out nothing qualifies. Band 7 (odd) is
  // empty, so order 7 leaves out nothing the pilot sees.
  EXPECT_EQ(c.order, 7);
  EXPECT_TRUE(c.reached);
  EXPECT_EQ(c.truncation_percent[6], 0.0);
  o.max_order = 7;  // band 6 is not empty: nothing below 7 qualifies, and the choice says so
  const OrderChoice e = s.choose(t, o);
  EXPECT_EQ(e.order, 7);
  EXPECT_FALSE(e.reached);
  o.max_order = 8;
  // A tolerance: the lowest order whose closed-form tail is under it. Odd bands above 1 are
  // empty, so orders 3 and 4 leave out the same.
  o.tolerance_percent = 100 * std::sqrt((band_energy(4) + band_energy(6)) / unit2) + 1e-6;
  const OrderChoice d = s.choose(t, o);
  EXPECT_EQ(d.order, 3);
  EXPECT_TRUE(d.reached);
  EXPECT_EQ(d.points, s.mesh.num_vertices());
  EXPECT_EQ(d.rays, 2 * 64 * s.mesh.num_vertices());
}

TEST(OrderChoice, UnderAConstantLightOneBandIsEnough) {
  // Only band 0 carries power: every higher band's error weighs nothing.
  const Scene s(test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  TransferOptions t;
  t.rays = 64;
  OrderChoiceOptions o;
  o.max_order = 6;
  o.band_power = {1, 0, 0, 0, 0, 0};
  const OrderChoice c = s.choose(t, o);
  EXPECT_EQ(c.order, 1);
  EXPECT_TRUE(c.reached);
  for (double e : c.truncation_percent) EXPECT_EQ(e, 0.0);
  o.band_power = {1, 0, 0};  // too few bands for max_order
  EXPECT_THROW(s.choose(t, o), InputError);
}

TEST(OrderChoice, TheNoiseFallsAsOneOverRootRaysAndMoreRaysKeepMoreBands) {
  const Scene s(test::merge(test::icosphere(2), test::quad(3.0, -1.05, true)));
  OrderChoiceOptions o;
  TransferOptions few, many;
  few.rays = 16, many.rays = 1024;
  const OrderChoice a = s.choose(few, o), b = s.choose(many, o);
  // 64 times the rays: at most an eighth of the noise, as independent rays would give; the
  // lattice's strata give less (0.023 measured), but not more than the integrand's smoothness
  // allows (a lattice's error falls no faster than 1/rays for a shadow's edge: 1/64).
  const double ratio = b.noise_percent.back() / a.noise_percent.back();
  EXPECT_LT(ratio, 0.125);
  EXPECT_GT(ratio, 1.0 / 64);
  EXPECT_LE(a.order, b.order);
  EXPECT_LT(a.order, 8);  // at 16 rays the higher bands drown in noise
}

TEST(OrderChoice, IsTheSameForAnyThreadCount) {
  const Scene s(test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  TransferOptions t;
  t.rays = 32, t.threads = 1;
  OrderChoiceOptions o;
  const OrderChoice a = s.choose(t, o);
  t.threads = 2;
  const OrderChoice b = s.choose(t, o);
  EXPECT_EQ(a.order, b.order);
  EXPECT_EQ(a.truncation_percent, b.truncation_percent);
  EXPECT_EQ(a.noise_percent, b.noise_percent);
}

TEST(OrderChoice, TheBakeRunsAtTheChosenOrderAndRecordsWhy) {
  const Mesh mesh = test::build(test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  BakeOptions o;
  o.transfer.rays = 16, o.fit.method = FitMethod::Point, o.order_auto = true;
  const BakeResult r = bake(mesh, o);
  ASSERT_GT(r.order.order, 0);
  EXPECT_EQ(r.transfer.cols(), sh_count(r.order.order));
  bool recorded = false;
  for (const auto& [key, value] : r.metadata) recorded |= key == "order_auto" && value.rfind(std::to_string(r.order.order) + " (", 0) == 0;
  EXPECT_TRUE(recorded);
  o.signal = AssetSignal::Ao;
  EXPECT_THROW(bake(mesh, o), InputError);
  o.signal = AssetSignal::Transfer, o.order_choice.max_order = 11;
  EXPECT_THROW(bake(mesh, o), InputError);
}

}  // namespace
}  // namespace prtsub
