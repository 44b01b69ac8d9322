#include "prtsub/prt/sh.h"

#include <gtest/gtest.h>

#include <cmath>

#include "helpers.h"

namespace prtsub {
namespace {

// Integrates f(ω) over the sphere (or the hemisphere about n) with a product rule:
// Gauss-Legendre in the polar cosine, uniform in azimuth. Exact for the polynomials here.
template <class F>
void sphere_quadrature(int n_polar, int n_azimuth, F&& f, const Eigen::Vector3d* hemisphere_normal = nullptr) {
  std::vector<double> x, w;
  test::gauss_legendre(n_polar, x, w);
  Eigen::Vector3d t(1, 0, 0), b(0, 1, 0), n(0, 0, 1);
  if (hemisphere_normal) {
    n = *hemisphere_normal;
    t = (std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(n).normalized();
    b = n.cross(t);
  }
  for (size_t i = 0; i < x.size(); ++i) {
    // Full sphere: cosθ = x. Hemisphere: cosθ = (x + 1)/2, weight halves.
    double c = hemisphere_normal ? 0.5 * (x[i] + 1) : x[i];
    double wc = hemisphere_normal ? 0.5 * w[i] : w[i];
    double s = std::sqrt(std::max(0.0, 1 - c * c));
    for (int j = 0; j < n_azimuth; ++j) {
      double phi = 2 * M_PI * (j + 0.5) / n_azimuth;
      Eigen::Vector3d d = s * std::cos(phi) * t + s * std::sin(phi) * b + c * n;
      f(d, wc * 2 * M_PI / n_azimuth);
    }
  }
}

TEST(SphericalHarmonics, OrthonormalByQuadratureThroughOrder10) {
  const int order = kMaxShOrder, K = sh_count(order);
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(K, K);
  sphere_quadrature(24, 48, [&](const Eigen::Vector3d& d, double w) {
    Eigen::VectorXd y = sh_eval(order, d);
    gram += w * y * y.transpose();
  });
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(K, K)).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(SphericalHarmonics, ClosedFormsThroughBand2WithPositiveSigns) {
  const double c0 = 0.5 * std::sqrt(1 / M_PI), c1 = std::sqrt(3 / (4 * M_PI));
  const double c2 = 0.5 * std::sqrt(15 / M_PI), c20 = 0.25 * std::sqrt(5 / M_PI), c22 = 0.25 * std::sqrt(15 / M_PI);
  for (uint64_t s = 0; s < 50; ++s) {
    Eigen::Vector3d d = test::random_direction(s);
    double x = d.x(), y = d.y(), z = d.z();
    Eigen::VectorXd v = sh_eval(3, d);
    EXPECT_NEAR(v[sh_index(0, 0)], c0, 1e-14);
    EXPECT_NEAR(v[sh_index(1, -1)], c1 * y, 1e-14);
    EXPECT_NEAR(v[sh_index(1, 0)], c1 * z, 1e-14);
    EXPECT_NEAR(v[sh_index(1, 1)], c1 * x, 1e-14);
    EXPECT_NEAR(v[sh_index(2, -2)], c2 * x * y, 1e-14);
    EXPECT_NEAR(v[sh_index(2, -1)], c2 * y * z, 1e-14);
    EXPECT_NEAR(v[sh_index(2, 0)], c20 * (3 * z * z - 1), 1e-14);
    EXPECT_NEAR(v[sh_index(2, 1)], c2 * x * z, 1e-14);
    EXPECT_NEAR(v[sh_index(2, 2)], c22 * (x * x - y * y), 1e-14);
  }
}

TEST(SphericalHarmonics, BandEnergyInvariantUnderRotation) {
  // A function made of weighted point lobes projects to Σ w_j y(d_j); rotating the lobes must
  // keep each band's energy, whatever the rotation.
  const int order = kMaxShOrder;
  std::vector<Eigen::Vector3d> dirs;
  std::vector<double> weights;
  for (uint64_t j = 0; j < 7; ++j) {
    dirs.push_back(test::random_direction(100 + j));
    weights.push_back(0.3 + 0.1 * static_cast<double>(j));
  }
  auto band_energy = [&](const Eigen::Matrix3d& R) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(sh_count(order));
    for (size_t j = 0; j < dirs.size(); ++j) c += weights[j] * sh_eval(order, R * dirs[j]);
    Eigen::VectorXd e(order);
    for (int l = 0; l < order; ++l) e[l] = c.segment(l * l, 2 * l + 1).squaredNorm();
    return e;
  };
  Eigen::VectorXd e0 = band_energy(Eigen::Matrix3d::Identity());
  for (uint64_t s = 0; s < 10; ++s) {
    Eigen::VectorXd e = band_energy(test::random_rotation(s));
    for (int l = 0; l < order; ++l) EXPECT_NEAR(e[l], e0[l], 1e-10 * (1 + e0[l])) << "band " << l;
  }
}

TEST(SphericalHarmonics, ClampedCosineBandsMatchKnownValues) {
  EXPECT_NEAR(clamped_cosine_band(0), M_PI, 1e-15);
  EXPECT_NEAR(clamped_cosine_band(1), 2 * M_PI / 3, 1e-15);
  EXPECT_NEAR(clamped_cosine_band(2), M_PI / 4, 1e-15);
  EXPECT_EQ(clamped_cosine_band(3), 0.0);
  EXPECT_NEAR(clamped_cosine_band(4), -M_PI / 24, 1e-15);
  EXPECT_EQ(clamped_cosine_band(5), 0.0);
  EXPECT_NEAR(clamped_cosine_band(6), M_PI / 64, 1e-15);
}

TEST(SphericalHarmonics, UnshadowedTransferMatchesHemisphereQuadratureForAnyNormal) {
  // ∫_{n·ω>0} (n·ω) y_i(ω) dω over the hemisphere about n: a polynomial integrand, exact.
  const int order = kMaxShOrder, K = sh_count(order);
  for (uint64_t s = 0; s < 12; ++s) {
    Eigen::Vector3d n = s == 0 ? Eigen::Vector3d(0, 0, -1) : s == 1 ? Eigen::Vector3d(0, 0, 1) : test::random_direction(s);
    Eigen::VectorXd q = Eigen::VectorXd::Zero(K);
    sphere_quadrature(16, 40, [&](const Eigen::Vector3d& d, double w) { q += w * n.dot(d) * sh_eval(order, d); }, &n);
    Eigen::VectorXd closed = unshadowed_transfer(order, n);
    EXPECT_LT((q - closed).cwiseAbs().maxCoeff(), 1e-10) << "normal " << n.transpose();
  }
}

}  // namespace
}  // namespace prtsub
