#include "prtsub/prt/lights.h"

#include <gtest/gtest.h>

#include "helpers.h"
#include "latlong.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

// ∫ f(ω) y(ω) dω by Gauss-Legendre in z (split at z = split) and uniform azimuth, for checks
// independent of the code under test.
template <class F>
Eigen::MatrixXd project(int order, F&& f, int n_polar = 48, int n_az = 96) {
  std::vector<double> x, w;
  test::gauss_legendre(n_polar, x, w);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(sh_count(order), 3);
  for (size_t i = 0; i < x.size(); ++i)
    for (int j = 0; j < n_az; ++j) {
      double z = x[i], s = std::sqrt(1 - z * z), phi = 2 * M_PI * (j + 0.5) / n_az;
      Eigen::Vector3d d(s * std::cos(phi), s * std::sin(phi), z);
      c += (w[i] * 2 * M_PI / n_az) * sh_eval(order, d) * f(d).transpose();
    }
  return c;
}

TEST(Lights, ConstantLightIsItsClosedForm) {
  ShLight l = constant_light(4, Eigen::Vector3d(1, 2, 3));
  EXPECT_NEAR(l.coeffs(0, 0), 2 * std::sqrt(M_PI), 1e-14);
  EXPECT_NEAR(l.coeffs(0, 2), 6 * std::sqrt(M_PI), 1e-14);
  EXPECT_EQ(l.coeffs.bottomRows(15).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Lights, RotationMatchesProjectingTheRotatedFunctionThroughOrder10) {
  // f = a random order-10 light; g(ω) = f(R⁻¹ω) projected by quadrature must equal the rotated
  // coefficients. The quadrature is exact for this polynomial degree.
  const int order = kMaxShOrder;
  ShLight f = random_light(order, 7);
  for (uint64_t s = 0; s < 3; ++s) {
    Eigen::Matrix3d R = test::random_rotation(s);
    Eigen::MatrixXd direct = project(order, [&](const Eigen::Vector3d& d) {
      Eigen::VectorXd y = sh_eval(order, R.transpose() * d);
      return Eigen::Vector3d((f.coeffs.transpose() * y));
    }, 24, 48);
    ShLight g = rotate_light(f, R);
    EXPECT_LT((direct - Eigen::MatrixXd(g.coeffs)).cwiseAbs().maxCoeff(), 1e-9) << "rotation " << s;
  }
  // Composition and the identity.
  Eigen::Matrix3d A = test::random_rotation(10), B = test::random_rotation(11);
  Eigen::MatrixXd MA = sh_rotation(order, A), MB = sh_rotation(order, B), MAB = sh_rotation(order, A * B);
  EXPECT_LT((MA * MB - MAB).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((sh_rotation(order, Eigen::Matrix3d::Identity()) - Eigen::MatrixXd::Identity(100, 100)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Lights, SunCapMatchesQuadratureAndRotatesWithItsDirection) {
  const int order = 6;
  const double radius = 20;  // degrees: a cap wide enough for the quadrature to resolve
  Eigen::Vector3d dir = Eigen::Vector3d(0, 0, 1);
  ShLight sun = sun_light(order, dir, radius);
  const double c = std::cos(radius * M_PI / 180), Ls = M_PI / (2 * M_PI * (1 - c));
  // Integrate the cap in its own frame: z ∈ [c, 1] with Gauss-Legendre, exact for polynomials.
  std::vector<double> x, w;
  test::gauss_legendre(32, x, w);
  Eigen::VectorXd direct = Eigen::VectorXd::Zero(sh_count(order));
  for (size_t i = 0; i < x.size(); ++i)
    for (int j = 0; j < 64; ++j) {
      double z = c + (1 - c) * 0.5 * (x[i] + 1), s = std::sqrt(1 - z * z), phi = 2 * M_PI * (j + 0.5) / 64;
      direct += Ls * 0.5 * (1 - c) * w[i] * (2 * M_PI / 64) * sh_eval(order, Eigen::Vector3d(s * std::cos(phi), s * std::sin(phi), z));
    }
  EXPECT_LT((sun.coeffs.col(0) - direct).cwiseAbs().maxCoeff(), 1e-10);
  // Irradiance at normal incidence is π: an unshadowed white surface facing it leaves radiance
  // (1/π)·l·t_unshadowed. For radius 0 the SH of a delta light give exactly π·y(d)·Â.
  ShLight delta = sun_light(order, Eigen::Vector3d(1, 2, 3), 0);
  Eigen::Vector3d d = Eigen::Vector3d(1, 2, 3).normalized();
  EXPECT_LT((delta.coeffs.col(1) - M_PI * sh_eval(order, d)).cwiseAbs().maxCoeff(), 1e-12);
  Eigen::Matrix3d R = test::random_rotation(3);
  ShLight rotated = rotate_light(sun_light(order, d, 5), R);
  EXPECT_LT((rotated.coeffs - sun_light(order, R * d, 5).coeffs).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(Lights, SkyMatchesQuadratureWithTheHorizonSplit) {
  const int order = 5;
  Eigen::Vector3d up = Eigen::Vector3d(0, 0, 1), zen(0.2, 0.4, 1), hor(1, 0.9, 0.8), gnd(0.1, 0.1, 0.1);
  ShLight sky = sky_light(order, up, zen, hor, gnd);
  // The profile jumps at the horizon: integrate each hemisphere with its own Gauss rule.
  std::vector<double> x, w;
  test::gauss_legendre(16, x, w);
  Eigen::MatrixXd direct = Eigen::MatrixXd::Zero(sh_count(order), 3);
  for (int half = 0; half < 2; ++half)
    for (size_t i = 0; i < x.size(); ++i)
      for (int j = 0; j < 64; ++j) {
        double z = half ? 0.5 * (x[i] + 1) : 0.5 * (x[i] - 1), s = std::sqrt(1 - z * z), phi = 2 * M_PI * (j + 0.5) / 64;
        Eigen::Vector3d L = half ? Eigen::Vector3d(hor + (zen - hor) * z) : gnd;
        direct += 0.5 * w[i] * (2 * M_PI / 64) * sh_eval(order, Eigen::Vector3d(s * std::cos(phi), s * std::sin(phi), z)) * L.transpose();
      }
  EXPECT_LT((Eigen::MatrixXd(sky.coeffs) - direct).cwiseAbs().maxCoeff(), 1e-12);
  // All colours equal: the constant light.
  Eigen::Vector3d g(0.5, 0.5, 0.5);
  EXPECT_LT((sky_light(order, up, g, g, g).coeffs - constant_light(order, g).coeffs).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(Lights, RandomLightsHaveUnitPowerAndDependOnTheSeed) {
  ShLight a = random_light(4, 1), b = random_light(4, 1), c = random_light(4, 2);
  EXPECT_NEAR(a.coeffs.col(0).norm(), 1.0, 1e-14);
  EXPECT_EQ(a.coeffs, b.coeffs);
  EXPECT_GT((a.coeffs - c.coeffs).cwiseAbs().maxCoeff(), 0.01);
}

TEST(Lights, EnvironmentMapsUseExactSolidAnglesAndTheDocumentedMapping) {
  // Constant map: exact solid angles sum to 4π, so l0 is exact.
  ShLight c = environment_light(4, test::latlong(16, 8, [](const Eigen::Vector3d&) { return Eigen::Vector3d(1, 1, 1); }));
  EXPECT_NEAR(c.coeffs(0, 0), 2 * std::sqrt(M_PI), 1e-12);
  EXPECT_LT(c.coeffs.bottomRows(15).cwiseAbs().maxCoeff(), 1e-12);
  // A linear map L = 1 + d·ω with d = (0.2, 0.5, -0.3): band 1 is sqrt(4π/3)·(d_y, d_z, d_x).
  // Sampling the texel centre makes an O(1/H²) error.
  Eigen::Vector3d d(0.2, 0.5, -0.3);
  ShLight lin = environment_light(3, test::latlong(256, 128, [&](const Eigen::Vector3d& w) { return Eigen::Vector3d::Constant(1 + d.dot(w)); }));
  const double k = std::sqrt(4 * M_PI / 3);
  EXPECT_NEAR(lin.coeffs(1, 0), k * d.y(), 2e-4);
  EXPECT_NEAR(lin.coeffs(2, 0), k * d.z(), 2e-4);
  EXPECT_NEAR(lin.coeffs(3, 0), k * d.x(), 2e-4);
  EXPECT_NEAR(lin.coeffs(0, 0), 2 * std::sqrt(M_PI), 1e-4);
  // The documented mapping: top row is +y, u = 0 is +x, u = 0.25 is -z.
  EXPECT_NEAR(latlong_direction(0.3, 0).y(), 1.0, 1e-12);
  EXPECT_NEAR(latlong_direction(0, 0.5).x(), 1.0, 1e-12);
  EXPECT_NEAR(latlong_direction(0.25, 0.5).z(), -1.0, 1e-12);
}

}  // namespace
}  // namespace prtsub
