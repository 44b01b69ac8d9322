// The path-traced reference against closed forms: in a hemispherical bowl a cosine-weighted ray
// from any point of the inside hits the inside with probability 1/2 (on a sphere, cosine-weighted
// rays land uniformly over its area), so under a constant light every point's radiance after B
// bounces at albedo ρ is (ρ/2) Σ_{k≤B} (ρ/2)^k, the white furnace's limit 1 at ρ = 1; a closed room
// lit by nothing is black; a plate's back is black; the two estimators agree; and the result is
// the same for any thread count.
#include "prtsub/prt/path_transfer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "helpers.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

struct Scene {
  Mesh mesh;
  RayScene rays;
  RowMatrixX3d corners;
  explicit Scene(const RawMesh& raw, double crease = 60)
      : mesh(test::build(raw, crease)), rays(mesh.positions, position_triangles(mesh)), corners(vertex_positions(mesh)) {}
  PathSurface surface() const { return {corners, mesh.normals, mesh.triangles}; }
};

// Centroids of the faces whose centroid has z below `below`, with interpolated normals.
void centroids(const Mesh& m, double below, RowMatrixX3d& points, RowMatrixX3d& normals) {
  std::vector<size_t> faces;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const Triangle& t = m.triangles[f];
    if ((m.point(t[0]).z() + m.point(t[1]).z() + m.point(t[2]).z()) / 3 < below) faces.push_back(f);
  }
  points.resize(static_cast<Eigen::Index>(faces.size()), 3);
  normals.resize(points.rows(), 3);
  for (size_t i = 0; i < faces.size(); ++i) {
    const Triangle& t = m.triangles[faces[i]];
    Eigen::Vector3d p = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
    for (uint32_t c : t) p += m.point(c) / 3, n += m.normals.row(c).transpose();
    points.row(static_cast<Eigen::Index>(i)) = p.transpose();
    normals.row(static_cast<Eigen::Index>(i)) = n.normalized().transpose();
  }
}

// Radiance under a constant light 1 of transfer with t0 (the light's only coefficient is √(4π)).
double radiance(double albedo, double t0) { return albedo / M_PI * std::sqrt(4 * M_PI) * t0; }

TEST(PathTransfer, TheBowlsRadianceFollowsItsClosedFormBounceByBounce) {
  const Scene s(test::bowl(3));
  RowMatrixX3d points, normals;
  centroids(s.mesh, -0.5, points, normals);
  ASSERT_GT(points.rows(), 100);
  const double n = static_cast<double>(points.rows());
  TransferOptions t;
  t.order = 1, t.rays = 2048;
  const RowMatrixXd direct = shadowed_transfer(s.rays, points, normals, t);
  // The open fraction q of each point's cosine-weighted rays: 1/2 on the sphere, a little less on
  // its 640-face approximation; every bounce then keeps the 1 − q that hit the inside.
  double q = 0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) q += direct(i, 0) / (std::sqrt(M_PI) / 2) / n;
  EXPECT_NEAR(q, 0.5, 0.02);  // 0.488 measured
  for (const double albedo : {0.5, 1.0}) {
    for (const int bounces : {1, 3}) {
      PathOptions p;
      p.order = 1, p.paths = 512, p.bounces = bounces, p.albedo = albedo;
      std::vector<double> var;
      const RowMatrixXd bounced = path_traced_transfer(s.rays, s.surface(), points, normals, p, &var);
      double want = 0;
      for (int k = 0; k <= bounces; ++k) want += albedo * q * std::pow(albedo * (1 - q), k);
      double mean = 0, mean_var = 0;
      for (Eigen::Index i = 0; i < points.rows(); ++i)
        mean += radiance(albedo, direct(i, 0) + bounced(i, 0)) / n, mean_var += var[static_cast<size_t>(i)];
      const double sigma = radiance(albedo, std::sqrt(mean_var) / n);  // the mean's noise
      EXPECT_NEAR(mean, want, 4 * sigma + 0.002 * want) << "albedo " << albedo << ", " << bounces << " bounces";
    }
  }
}

TEST(PathTransfer, AClosedRoomLitByNothingStaysExactlyBlack) {
  const Scene s(test::closed_room(), 0);
  RowMatrixX3d points, normals;
  centroids(s.mesh, 2, points, normals);
  for (const bool plain : {false, true}) {
    PathOptions p;
    p.order = 3, p.paths = 64, p.bounces = 8, p.albedo = 1, p.plain = plain;
    const RowMatrixXd t = path_traced_transfer(s.rays, s.surface(), points, normals, p);
    EXPECT_EQ(t.cwiseAbs().maxCoeff(), 0.0) << plain;
  }
}

TEST(PathTransfer, BackFacesAreBlackAndTheOpenSkyBouncesNothing) {
  // A ground, and a plate above it: facing down, the ground sees its front and receives its
  // light; facing up, the ground sees the plate's back and receives nothing.
  for (const bool plate_up : {true, false}) {
    const Scene s(test::merge(test::quad(2.0, 0.0, true), test::quad(1.0, 0.5, plate_up)));
    RowMatrixX3d points(3, 3), normals(3, 3);
    points << 0, 0, 0, 0.3, -0.2, 0, 0.1, 0.1, 0.5;  // two on the ground, one on the plate's top side
    normals << 0, 0, 1, 0, 0, 1, 0, 0, 1;
    PathOptions p;
    p.order = 2, p.paths = 256, p.bounces = 2;
    const RowMatrixXd bounced = path_traced_transfer(s.rays, s.surface(), points, normals, p);
    if (plate_up) EXPECT_EQ(bounced.topRows(2).cwiseAbs().maxCoeff(), 0.0);
    else EXPECT_GT(bounced.row(0).norm(), 0.05);
    // Above the plate (it faces up or not) nothing blocks the sky: nothing bounces there. With a
    // plate facing down the point sits on its back, under the sky all the same.
    EXPECT_EQ(bounced.row(2).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(PathTransfer, BothEstimatorsAgreeWithinTheirNoise) {
  // A sphere resting over a ground: contact shadows and light bouncing between the two.
  const Scene s(test::merge(test::icosphere(2), test::quad(3.0, -1.02, true)));
  ReferenceOptions ro;
  ro.points = 150, ro.rays = 2, ro.noise_points = 0;
  const Reference at = make_reference(s.mesh, s.rays, ro);
  TransferOptions t;
  t.order = 3, t.rays = 1024;
  std::vector<double> var_direct, var_split, var_plain;
  RowMatrixXd split = shadowed_transfer(s.rays, at.points, at.normals, t, nullptr, {}, nullptr, &var_direct);
  PathOptions p;
  p.order = 3, p.paths = 2048, p.bounces = 2, p.albedo = 0.9, p.seed = 1;
  split += path_traced_transfer(s.rays, s.surface(), at.points, at.normals, p, &var_split);
  p.paths = 1 << 12, p.plain = true, p.seed = 2;
  const RowMatrixXd plain = path_traced_transfer(s.rays, s.surface(), at.points, at.normals, p, &var_plain);
  double diff2 = 0, var = 0;
  for (Eigen::Index i = 0; i < at.points.rows(); ++i) {
    const auto k = static_cast<size_t>(i);
    diff2 += (split.row(i) - plain.row(i)).squaredNorm();
    var += var_direct[k] + var_split[k] + var_plain[k];
  }
  // 150 points × 9 coefficients: the ratio of a sum of squares to its expectation spreads by a
  // few percent; a bias the size of the noise would double it.
  EXPECT_GT(diff2 / var, 0.75);
  EXPECT_LT(diff2 / var, 1.3);
}

TEST(PathTransfer, IsTheSameForAnyThreadCount) {
  const Scene s(test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  ReferenceOptions ro;
  ro.points = 50, ro.rays = 2, ro.noise_points = 0;
  const Reference at = make_reference(s.mesh, s.rays, ro);
  for (const bool plain : {false, true}) {
    PathOptions p;
    p.order = 3, p.paths = 64, p.bounces = 3, p.plain = plain, p.threads = 1;
    const RowMatrixXd one = path_traced_transfer(s.rays, s.surface(), at.points, at.normals, p);
    p.threads = 2;
    EXPECT_EQ(one, path_traced_transfer(s.rays, s.surface(), at.points, at.normals, p)) << plain;
  }
}

TEST(PathTransfer, RefusesOptionsOutOfRange) {
  const Scene s(test::quad(1.0, 0.0, true));
  RowMatrixX3d points(1, 3), normals(1, 3);
  points << 0, 0, 0;
  normals << 0, 0, 1;
  const auto with = [&](auto change) {
    PathOptions p;
    change(p);
    return path_traced_transfer(s.rays, s.surface(), points, normals, p);
  };
  EXPECT_THROW(with([](PathOptions& p) { p.paths = 0; }), InputError);
  EXPECT_THROW(with([](PathOptions& p) { p.bounces = 65; }), InputError);
  EXPECT_THROW(with([](PathOptions& p) { p.albedo = 1.5; }), InputError);
  EXPECT_THROW(with([](PathOptions& p) { p.albedo = NAN; }), InputError);
  EXPECT_THROW(with([](PathOptions& p) { p.order = 11; }), InputError);
  RowMatrixX3d two(2, 3);
  two.setZero();
  EXPECT_THROW(path_traced_transfer(s.rays, s.surface(), points, two, PathOptions{}), InputError);
}

}  // namespace
}  // namespace prtsub
