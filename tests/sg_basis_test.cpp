#include "prtsub/prt/sg_basis.h"

#include <gtest/gtest.h>

#include <cmath>

#include "helpers.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

// Legendre P_l(t) by the three-term recurrence.
double legendre(int l, double t) {
  double p0 = 1, p1 = t;
  if (l == 0) return p0;
  for (int n = 1; n < l; ++n) {
    const double p2 = ((2 * n + 1) * t * p1 - n * p0) / (n + 1);
    p0 = p1, p1 = p2;
  }
  return p1;
}

// ∫ f over the sphere by a product rule: 96 Gauss–Legendre nodes in z, 192 azimuths. Exact for
// the band-limited and smooth integrands below to far better than the tolerances.
template <class F>
double sphere_integral(F f) {
  std::vector<double> x, w;
  test::gauss_legendre(96, x, w);
  double sum = 0;
  const int na = 192;
  for (size_t i = 0; i < x.size(); ++i) {
    const double z = x[i], r = std::sqrt(1 - z * z);
    for (int j = 0; j < na; ++j) {
      const double phi = 2 * M_PI * (j + 0.5) / na;
      sum += w[i] * (2 * M_PI / na) * f(Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z));
    }
  }
  return sum;
}

TEST(SgBasis, TheLobeSetIsFixedByItsCount) {
  // The documented rule: Fibonacci axes, λ = ln 2 / (1 − cos(θ/2)), θ = √(4π/N).
  for (int N : {9, 12}) {
    const SgBasis b = sg_basis(N);
    ASSERT_EQ(b.size(), N);
    EXPECT_NEAR(b.sharpness, std::log(2.0) / (1 - std::cos(std::sqrt(4 * M_PI / N) / 2)), 1e-12);
    double closest = 4;
    for (int i = 0; i < N; ++i) {
      EXPECT_NEAR(b.axes[size_t(i)].norm(), 1.0, 1e-12);
      for (int j = 0; j < i; ++j) closest = std::min(closest, (b.axes[size_t(i)] - b.axes[size_t(j)]).norm());
    }
    EXPECT_GT(closest, 0.6 * std::sqrt(4 * M_PI / N));  // spread out: no two axes bunch up
    // Half the peak halfway to a neighbour at the mean spacing, and the peak on the axis.
    double g[64];
    const double half = std::sqrt(4 * M_PI / N) / 2;
    const Eigen::Vector3d a = b.axes[0], t = a.unitOrthogonal();
    sg_eval(b, std::cos(half) * a + std::sin(half) * t, g);
    EXPECT_NEAR(g[0], 0.5, 1e-12);
    sg_eval(b, a, g);
    EXPECT_NEAR(g[0], 1.0, 1e-15);
  }
  EXPECT_NEAR(sg_basis(9).sharpness, 4.089, 1e-3);
  EXPECT_NEAR(sg_basis(12).sharpness, 5.412, 1e-3);
  EXPECT_THROW(sg_basis(3), InputError);
  EXPECT_THROW(sg_basis(65), InputError);
}

TEST(SgBasis, ZonalCoefficientsMatchQuadratureOfTheLegendreIntegral) {
  std::vector<double> x, w;
  test::gauss_legendre(128, x, w);
  for (double lambda : {0.3, 4.089, 5.412, 30.0}) {
    const std::vector<double> g = sg_zonal(lambda, 10);
    for (int l = 0; l < 10; ++l) {
      double q = 0;
      for (size_t i = 0; i < x.size(); ++i) q += 2 * M_PI * w[i] * legendre(l, x[i]) * std::exp(lambda * (x[i] - 1));
      EXPECT_NEAR(g[size_t(l)], q, 1e-11 * g[0]) << "λ " << lambda << " l " << l;
    }
    // l = 0 in closed form: 4π e^{−λ} sinh(λ)/λ.
    EXPECT_NEAR(g[0], 4 * M_PI * std::exp(-lambda) * std::sinh(lambda) / lambda, 1e-12 * g[0]);
  }
  EXPECT_THROW(sg_zonal(0, 4), InputError);
  EXPECT_THROW(sg_zonal(1, 0), InputError);
}

TEST(SgBasis, TheGramMatrixIsTheLobesProductIntegrated) {
  const SgBasis b = sg_basis(9);
  const Eigen::MatrixXd G = sg_gram(b);
  for (int i : {0, 4, 8})
    for (int j : {0, 3, 8}) {
      const double q = sphere_integral([&](const Eigen::Vector3d& v) {
        double s[64];
        sg_eval(b, v, s);
        return s[i] * s[j];
      });
      EXPECT_NEAR(G(i, j), q, 1e-9 * G(0, 0)) << i << " " << j;
    }
  EXPECT_GT(G(0, 1), 0.05 * G(0, 0));  // neighbours overlap: not orthogonal
}

TEST(SgBasis, AnShLightProjectsOntoTheLobesInClosedForm) {
  // ∫ L(ω) G_k(ω) dω for a random order-6 light, by quadrature, against Funk–Hecke.
  const SgBasis b = sg_basis(12);
  const ShLight light = random_light(6, 7);
  const auto closed = sg_light(b, light);
  for (int k : {0, 5, 11})
    for (int c = 0; c < 3; ++c) {
      const double q = sphere_integral([&](const Eigen::Vector3d& v) {
        double s[64];
        sg_eval(b, v, s);
        return s[k] * sh_eval(6, v).dot(light.coeffs.col(c));
      });
      EXPECT_NEAR(closed(k, c), q, 1e-9 * std::max(1.0, std::abs(q))) << k << " " << c;
    }
}

TEST(SgBasis, AnEnvironmentMapProjectsAsItsShLightDoes) {
  // A constant map: every lobe sees c ∫ G = c · 4π e^{−λ} sinh(λ)/λ. A map that is an order-3
  // SH light sampled per texel: the same as the light's closed form, to the map's resolution.
  const SgBasis b = sg_basis(9);
  Image flat{16, 8, 3, std::vector<float>(16 * 8 * 3, 0.5f)};
  const auto lf = sg_light(b, flat);
  const double lobe = 4 * M_PI * std::exp(-b.sharpness) * std::sinh(b.sharpness) / b.sharpness;
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(lf(k, 1), 0.5 * lobe, 1e-6 * lobe);
  const ShLight light = random_light(3, 11);
  Image img{256, 128, 3, std::vector<float>(256 * 128 * 3)};
  for (int r = 0; r < img.height; ++r)
    for (int c = 0; c < img.width; ++c) {
      const Eigen::VectorXd y = sh_eval(3, latlong_direction((c + 0.5) / img.width, (r + 0.5) / img.height));
      for (int ch = 0; ch < 3; ++ch) img.at(c, r, ch) = float(y.dot(light.coeffs.col(ch)));
    }
  const auto from_map = sg_light(b, img), closed = sg_light(b, light);
  EXPECT_LT((from_map - closed).cwiseAbs().maxCoeff(), 0.01 * closed.cwiseAbs().maxCoeff());
  Image bad{1, 1, 2, {0.f, 0.f}};
  EXPECT_THROW(sg_light(b, bad), InputError);
}

}  // namespace
}  // namespace prtsub

#include "prtsub/prt/transfer.h"

namespace prtsub {
namespace {

// The exact least-squares (or non-negative least-squares, by enumerating supports) fit of the
// clamped cosine about n in the lobes: Gram in closed form, moments by quadrature.
Eigen::VectorXd exact_sg_fit(const SgBasis& b, const Eigen::Vector3d& n, bool non_negative) {
  const int N = b.size();
  const Eigen::MatrixXd G = sg_gram(b);
  Eigen::VectorXd m(N);
  for (int k = 0; k < N; ++k)
    m[k] = sphere_integral([&](const Eigen::Vector3d& v) {
      double s[64];
      sg_eval(b, v, s);
      return s[k] * std::max(0.0, v.dot(n));
    });
  return non_negative ? test::nnls_by_enumeration(G, m) : Eigen::VectorXd(G.ldlt().solve(m));
}

TEST(SgTransfer, AnOpenPointEncodesTheClampedCosineAsTheNonNegativeFitDoes) {
  // Vertices of a convex icosphere see the whole sky. Their lobes, from 4096 rays, against the
  // exact non-negative fit: relit by random order-6 lights, within 2% of the exact fit's shading
  // (the encoder's noise is about ‖c‖/√(2R) ≈ 1%), and the exact fit itself within a few
  // percent of the truth (Σ l_i t_u,i): 9 lobes cannot hold a clamped cosine exactly.
  const Mesh m = test::build(test::icosphere(1));
  const RayScene scene(m.positions, position_triangles(m));
  const SgBasis b = sg_basis(9);
  TransferOptions o;
  o.rays = 4096;
  o.progressive.non_negative = true;
  const RowMatrixX3d p = vertex_positions(m);
  const RowMatrixXd c = sg_transfer(scene, p, m.normals, b, o);
  EXPECT_GE(c.minCoeff(), 0.0);
  for (Eigen::Index v : {0, 5, 20}) {
    const Eigen::Vector3d n = m.normals.row(v).transpose();
    const Eigen::VectorXd exact = exact_sg_fit(b, n, true);
    for (uint64_t seed : {1, 2, 3}) {
      const ShLight light = random_light(6, seed);
      const auto L = sg_light(b, light);
      const double encoded = c.row(v).dot(L.col(0)), fitted = exact.dot(L.col(0));
      const double truth = unshadowed_transfer(6, n).dot(light.coeffs.col(0));
      const double scale = std::abs(truth) + light.coeffs.col(0).norm();
      std::printf("vertex %ld light %lu: encoded %.4f, exact fit %.4f, truth %.4f\n", long(v), (unsigned long)seed, encoded, fitted, truth);
      EXPECT_NEAR(encoded, fitted, 0.02 * scale);
      EXPECT_NEAR(fitted, truth, 0.1 * scale);
    }
  }
  // The same for any thread count.
  o.threads = 1;
  const RowMatrixXd one = sg_transfer(scene, p, m.normals, b, o);
  o.threads = 2;
  EXPECT_EQ(one, sg_transfer(scene, p, m.normals, b, o));
}

TEST(SgTransfer, AnEnclosedPointIsExactlyZeroAndBadOptionsAreRefused) {
  const Mesh m = test::build(test::quad(1e4, 1.0, false));
  const RayScene scene(m.positions, position_triangles(m));
  RowMatrixX3d p(2, 3), n(2, 3);
  p << 0, 0, 0, 5, -3, 0.5;
  n << 0, 0, 1, 0, 0, 1;
  TransferOptions o;
  o.rays = 64;
  EXPECT_EQ(sg_transfer(scene, p, n, sg_basis(12), o).cwiseAbs().maxCoeff(), 0.0);
  o.rays = 0;
  EXPECT_THROW(sg_transfer(scene, p, n, sg_basis(12), o), InputError);
  o.rays = 64;
  EXPECT_THROW(sg_transfer(scene, p, n, SgBasis{}, o), InputError);
}

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

TEST(SgBasis, LobesConvertToShThatRelightsThemExactlyAtItsOrder) {
  // For any coefficients and any light of the order, Σ_i l_i t_i of the converted transfer equals
  // Σ_k c_k L_k; and each converted row is the lobes' sum projected by quadrature.
  const SgBasis b = sg_basis(12);
  RowMatrixXd c(3, 12);
  for (Eigen::Index i = 0; i < c.size(); ++i) c.data()[i] = std::sin(0.7 * double(i) + 1);
  const RowMatrixXd t = sg_to_sh(b, c, 5);
  ASSERT_EQ(t.cols(), 25);
  for (uint64_t seed : {1, 2}) {
    const ShLight light = random_light(5, seed);
    const Eigen::VectorXd via_sh = t * light.coeffs.col(0), via_lobes = c * sg_light(b, light).col(0);
    EXPECT_LT((via_sh - via_lobes).cwiseAbs().maxCoeff(), 1e-12 * (1 + via_lobes.cwiseAbs().maxCoeff()));
  }
  for (int i : {0, 7, 24}) {
    const double q = sphere_integral([&](const Eigen::Vector3d& v) {
      double s[64];
      sg_eval(b, v, s);
      return Eigen::Map<const Eigen::VectorXd>(s, 12).dot(c.row(1).transpose()) * sh_eval(5, v)[i];
    });
    EXPECT_NEAR(t(1, i), q, 1e-9 * (1 + std::abs(q))) << i;
  }
  EXPECT_THROW(sg_to_sh(b, RowMatrixXd(2, 9), 4), InputError);
  EXPECT_THROW(sg_to_sh(b, c, 0), InputError);
}

}  // namespace
}  // namespace prtsub
