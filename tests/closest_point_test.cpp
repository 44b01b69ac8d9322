#include "prtsub/prt/closest_point.h"

#include <gtest/gtest.h>

#include "helpers.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"

namespace prtsub {
namespace {

TEST(ClosestPoint, AgreesWithBruteForceOverEveryFace) {
  // Points around and inside a sphere far from the origin, against the brute-force minimum.
  Mesh m = test::build(test::transformed(test::icosphere(2), 3.0, Eigen::Vector3d(1e4, -2e3, 5e2)));
  RowMatrixX3d q(2000, 3);
  for (Eigen::Index i = 0; i < q.rows(); ++i) {
    Rng r(11, uint64_t(i));
    q.row(i) << 1e4 + 8 * (r.uniform() - 0.5), -2e3 + 8 * (r.uniform() - 0.5), 5e2 + 8 * (r.uniform() - 0.5);
  }
  const std::vector<SurfaceLocation> at = closest_points(m, q, 2);
  ASSERT_EQ(at.size(), 2000u);
  for (Eigen::Index i = 0; i < q.rows(); ++i) {
    const Eigen::Vector3d p = q.row(i).transpose();
    double best = 1e300;
    for (const Triangle& t : m.triangles) {
      const Eigen::Vector3d w = closest_on_triangle(p, m.point(t[0]), m.point(t[1]), m.point(t[2]));
      best = std::min(best, (w[0] * m.point(t[0]) + w[1] * m.point(t[1]) + w[2] * m.point(t[2]) - p).norm());
    }
    const SurfaceLocation& l = at[size_t(i)];
    const Triangle& t = m.triangles[l.face];
    const Eigen::Vector3d x = l.barycentric[0] * m.point(t[0]) + l.barycentric[1] * m.point(t[1]) + l.barycentric[2] * m.point(t[2]);
    EXPECT_NEAR(l.distance, best, 1e-9);
    EXPECT_NEAR((x - p).norm(), best, 1e-9);
    EXPECT_GE(l.barycentric.minCoeff(), 0.0);
    EXPECT_NEAR(l.barycentric.sum(), 1.0, 1e-12);
  }
  // The same for one thread; points on the surface are found at distance 0.
  const std::vector<SurfaceLocation> one = closest_points(m, q, 1);
  for (size_t i = 0; i < at.size(); ++i) EXPECT_EQ(one[i].face, at[i].face);
  RowMatrixX3d corners = vertex_positions(m).topRows(10);
  for (const SurfaceLocation& l : closest_points(m, corners)) EXPECT_LT(l.distance, 1e-12);
}

// A thin slab (the unit cube squashed to 1% thick, z in [0, 0.01]): a point on its underside,
// facing down, is nearer to the top once it sits above the slab's middle, as a simplified
// surface's point may. Given normals, each is located on the faces that face its way.
TEST(ClosestPoint, GivenNormalsAPointIsLocatedOnTheSideItFaces) {
  RawMesh slab = test::cube();
  slab.positions.col(2) *= 0.01;
  const Mesh m = test::build(slab, 30.0);
  RowMatrixX3d q(3, 3), n(3, 3);
  q << 0.3, 0.4, 0.007, 0.3, 0.4, 0.007, 0.3, 0.4, 0.007;
  n << 0, 0, -1, 0, 0, 1, 1, 0, 0;
  const std::vector<SurfaceLocation> plain = closest_points(m, q), facing = closest_points(m, q, 1, &n);
  auto z = [&](const SurfaceLocation& l) {
    const Triangle& t = m.triangles[l.face];
    return l.barycentric[0] * m.point(t[0]).z() + l.barycentric[1] * m.point(t[1]).z() + l.barycentric[2] * m.point(t[2]).z();
  };
  EXPECT_NEAR(z(plain[0]), 0.01, 1e-12) << "unfiltered: the top is nearer";
  EXPECT_NEAR(plain[0].distance, 0.003, 1e-12);
  EXPECT_NEAR(z(facing[0]), 0.0, 1e-12) << "facing down: the underside";
  EXPECT_NEAR(facing[0].distance, 0.007, 1e-12);
  EXPECT_NEAR(z(facing[1]), 0.01, 1e-12) << "facing up: the top";
  EXPECT_NEAR(facing[2].distance, 0.7, 1e-12) << "facing +x: only the wall at x = 1";
  const RowMatrixX3d two = n.topRows(2);
  EXPECT_THROW(closest_points(m, q, 1, &two), InputError);
}

TEST(ClosestPoint, TriangleRegionsAndBadInput) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(closest_on_triangle({-1, -1, 3}, a, b, c).isApprox(Eigen::Vector3d(1, 0, 0)));        // corner a
  EXPECT_TRUE(closest_on_triangle({0.5, -2, 0}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0.5, 0)));   // edge ab
  EXPECT_TRUE(closest_on_triangle({1, 1, 0}, a, b, c).isApprox(Eigen::Vector3d(0, 0.5, 0.5)));      // edge bc
  EXPECT_TRUE(closest_on_triangle({0.25, 0.25, -5}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0.25, 0.25)));  // inside
  Mesh m = test::build(test::cube());
  RowMatrixX3d bad(1, 3);
  bad << 0, NAN, 0;
  EXPECT_THROW(closest_points(m, bad), InputError);
}

}  // namespace
}  // namespace prtsub
