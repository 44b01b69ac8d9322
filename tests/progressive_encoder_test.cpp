#include "prtsub/prt/progressive_encoder.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "helpers.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"

namespace prtsub {
namespace {

Eigen::Vector3d uniform_sphere(Rng& rng) {
  const double z = 1 - 2 * rng.uniform(), phi = 2 * M_PI * rng.uniform(), r = std::sqrt(std::max(0.0, 1 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Four spherical Gaussians, exp(λ(μ·ω − 1)), λ = 2: wide enough that neighbours overlap
// strongly (Gram off-diagonals up to 0.5 of the diagonal), so a diagonal projection is far off.
struct Lobes {
  static constexpr int K = 4;
  Eigen::Vector3d axis[K] = {{0, 0, 1}, {0.9428, 0, -0.3333}, {-0.4714, 0.8165, -0.3333}, {-0.4714, -0.8165, -0.3333}};
  double lambda = 2;
  void eval(const Eigen::Vector3d& w, double* out) const {
    for (int i = 0; i < K; ++i) out[i] = std::exp(lambda * (axis[i].normalized().dot(w) - 1));
  }
  // ∫ B_i B_j dω/4π for two lobes: a single lobe of axis λμ_i + λμ_j, in closed form.
  double gram(int i, int j) const {
    const double r = (lambda * axis[i].normalized() + lambda * axis[j].normalized()).norm();
    const double e = std::exp(-2 * lambda);
    return r < 1e-12 ? e : e * std::sinh(r) / r;
  }
  std::vector<double> mean_square() const {
    std::vector<double> m(K);
    for (int i = 0; i < K; ++i) m[size_t(i)] = gram(i, i);
    return m;
  }
};

double smooth(const Eigen::Vector3d& w) { return std::max(0.0, w.z()) + 0.3 * w.x() * w.x(); }
// Sharper than any lobe: its unconstrained fit takes light away below with negative lobes.
double sharp(const Eigen::Vector3d& w) { return std::pow(std::max(0.0, w.z()), 8); }
using Target = double (*)(const Eigen::Vector3d&);

// The exact least-squares fit of `target` in the lobes: G b = m with G in closed form and m by a
// fine product quadrature (Gauss–Legendre in z, 2048 azimuths), independent of the encoder.
Eigen::Vector4d exact_fit(const Lobes& L, bool non_negative, Target target = smooth) {
  Eigen::Matrix4d G;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) G(i, j) = L.gram(i, j);
  Eigen::Vector4d m = Eigen::Vector4d::Zero();
  const int nz = 400, na = 2048;
  for (int a = 0; a < nz; ++a) {
    // Midpoint rule in z: the integrand's kink at z = 0 falls on a cell boundary.
    const double z = -1 + (a + 0.5) * 2.0 / nz, r = std::sqrt(1 - z * z);
    for (int b = 0; b < na; ++b) {
      const double phi = 2 * M_PI * (b + 0.5) / na;
      const Eigen::Vector3d w(r * std::cos(phi), r * std::sin(phi), z);
      double B[4];
      L.eval(w, B);
      for (int i = 0; i < 4; ++i) m[i] += B[i] * target(w) / (nz * na);
    }
  }
  if (!non_negative) return G.ldlt().solve(m);
  return test::nnls_by_enumeration(G, m);
}

Eigen::Vector4d encode(const Lobes& L, const ProgressiveOptions& o, int samples, uint64_t seed, bool check_non_negative = false,
                       Target target = smooth) {
  ProgressiveEncoder e(4, 1, o, L.mean_square(), std::vector<double>(4, 1.0));
  Rng rng(seed, 0);
  for (int s = 0; s < samples; ++s) {
    const Eigen::Vector3d w = uniform_sphere(rng);
    double B[4], f = target(w);
    L.eval(w, B);
    e.add(B, &f);
    if (check_non_negative) {
      for (double c : e.coefficients()) EXPECT_GE(c, 0.0) << "after sample " << s;
    }
  }
  return Eigen::Vector4d(e.coefficients().data());
}

TEST(ProgressiveEncoder, OneSampleFollowsTheUpdateInClosedForm) {
  // With one sample s = 1: the Interpolated denominator is the start value, the Running one is
  // B_i², the Clamped one max(B_i², mean square). Jacobi corrects every function by the same
  // residual Δ = f; Gauss–Seidel shrinks Δ after each.
  const double B[2] = {0.5, 0.25}, f = 2.0, alpha = 1.5;
  for (auto den : {ProgressiveOptions::Denominator::Interpolated, ProgressiveOptions::Denominator::Running,
                   ProgressiveOptions::Denominator::Clamped})
    for (bool gs : {false, true}) {
      ProgressiveOptions o;
      o.acceleration = alpha, o.gauss_seidel = gs, o.denominator = den;
      ProgressiveEncoder e(2, 1, o, {0.1, 0.1}, {1.0, 2.0});
      e.add(B, &f);
      double delta = f, expect[2];
      for (int i = 0; i < 2; ++i) {
        const double start = i == 0 ? 1.0 : 2.0;
        const double I = den == ProgressiveOptions::Denominator::Interpolated ? start
                         : den == ProgressiveOptions::Denominator::Running    ? B[i] * B[i]
                                                                              : std::max(B[i] * B[i], 0.1);
        expect[i] = alpha * B[i] * delta / I;
        if (gs) delta -= expect[i] * B[i];
      }
      EXPECT_NEAR(e.coefficients()[0], expect[0], 1e-15);
      EXPECT_NEAR(e.coefficients()[1], expect[1], 1e-15);
    }
}

TEST(ProgressiveEncoder, ConvergesToTheLeastSquaresFitOfOverlappingLobes) {
  // 200,000 uniform samples. The encoder's error against the exact fit shrinks as the samples
  // grow (a 1/k step: noise about ‖b‖/√k; 8 of those bound it), and ends far closer than the
  // diagonal projection m_i / G_ii, which ignores the overlap.
  Lobes L;
  const Eigen::Vector4d exact = exact_fit(L, false);
  Eigen::Vector4d diagonal;
  {
    Eigen::Matrix4d G;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) G(i, j) = L.gram(i, j);
    diagonal = (G * exact).cwiseQuotient(G.diagonal());
  }
  ProgressiveOptions o;
  const double early = (encode(L, o, 2000, 7) - exact).norm(), late = (encode(L, o, 200000, 7) - exact).norm();
  std::printf("|error| at 2k %.4g, at 200k %.4g; diagonal projection %.4g\n", early, late, (diagonal - exact).norm());
  EXPECT_LT(late, 8 * exact.norm() / std::sqrt(200000.0));
  EXPECT_LT(late, 0.5 * early);
  EXPECT_GT((diagonal - exact).norm(), 10 * late);
  // Jacobi on the same lobes, with acceleration 3 and the other denominators: each converges too.
  for (bool gs : {false, true})
    for (double a : {1.0, 3.0})
      for (auto den : {ProgressiveOptions::Denominator::Running, ProgressiveOptions::Denominator::Clamped}) {
        ProgressiveOptions p;
        p.gauss_seidel = gs, p.acceleration = a, p.denominator = den;
        const double err = (encode(L, p, 200000, 11) - exact).norm();
        std::printf("gs %d alpha %.0f den %d: %.4g\n", gs, a, int(den), err);
        EXPECT_LT(err, 0.05 * exact.norm());
      }
}

TEST(ProgressiveEncoder, NonNegativeKeepsEveryCoefficientAtZeroOrAboveAndFindsTheClampedFit) {
  Lobes L;
  const Eigen::Vector4d exact = exact_fit(L, false, sharp), nn = exact_fit(L, true, sharp);
  std::printf("unconstrained %.4f %.4f %.4f %.4f; non-negative %.4f %.4f %.4f %.4f\n", exact[0], exact[1], exact[2], exact[3], nn[0], nn[1],
              nn[2], nn[3]);
  ASSERT_LT(exact.minCoeff(), -0.05);  // the constraint binds, so the test has power
  ProgressiveOptions o;
  o.non_negative = true;
  const Eigen::Vector4d b = encode(L, o, 200000, 3, true, sharp);
  std::printf("encoded %.4f %.4f %.4f %.4f\n", b[0], b[1], b[2], b[3]);
  EXPECT_LT((b - nn).norm(), 0.05 * nn.norm());
}

TEST(ProgressiveEncoder, OnlyRatiosOfWeightsMatter) {
  Lobes L;
  ProgressiveOptions o;
  ProgressiveEncoder one(4, 2, o, L.mean_square(), std::vector<double>(4, 1.0)), scaled = one;
  Rng rng(5, 0);
  for (int s = 0; s < 500; ++s) {
    const Eigen::Vector3d w = uniform_sphere(rng);
    double B[4], f[2] = {smooth(w), -w.y()};
    L.eval(w, B);
    const double weight = 0.5 + rng.uniform();
    one.add(B, f, weight);
    scaled.add(B, f, 1000 * weight);
  }
  for (size_t i = 0; i < 8; ++i) EXPECT_NEAR(one.coefficients()[i], scaled.coefficients()[i], 1e-12 * std::abs(one.coefficients()[i]) + 1e-14);
  EXPECT_NEAR(scaled.total_weight(), 1000 * one.total_weight(), 1e-9 * scaled.total_weight());
}

TEST(ProgressiveEncoder, RecoversAFunctionInTheSpanOfOrthonormalSH) {
  // The least-squares residual is zero, so the corrections die out as the estimate nears it.
  const int order = 3, K = sh_count(order);
  Eigen::VectorXd truth(K);
  for (int i = 0; i < K; ++i) truth[i] = std::sin(1.0 + i);
  std::vector<double> start(static_cast<size_t>(K), 0.0);
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) start[size_t(sh_index(l, m))] = (2 * l + 1) / (4 * M_PI);
  ProgressiveEncoder e(K, 1, ProgressiveOptions{}, std::vector<double>(size_t(K), 1 / (4 * M_PI)), start);
  Rng rng(9, 0);
  double y[9];
  for (int s = 0; s < 50000; ++s) {
    const Eigen::Vector3d w = uniform_sphere(rng);
    sh_eval(order, w.x(), w.y(), w.z(), y);
    const double f = Eigen::Map<const Eigen::VectorXd>(y, K).dot(truth);
    e.add(y, &f);
  }
  const double err = (Eigen::Map<const Eigen::VectorXd>(e.coefficients().data(), K) - truth).norm();
  std::printf("SH order 3 in span: error %.3g of %.3g\n", err, truth.norm());
  EXPECT_LT(err, 1e-3 * truth.norm());
}

TEST(ProgressiveEncoder, RejectsBadShapes) {
  ProgressiveOptions o;
  EXPECT_THROW(ProgressiveEncoder(0, 1, o, {}, {}), InputError);
  EXPECT_THROW(ProgressiveEncoder(2, 1, o, {1.0}, {1.0, 1.0}), InputError);
  EXPECT_THROW(ProgressiveEncoder(1, 1, o, {0.0}, {1.0}), InputError);
  EXPECT_THROW(ProgressiveEncoder(1, 1, o, {1.0}, {NAN}), InputError);
  o.acceleration = 0;
  EXPECT_THROW(ProgressiveEncoder(1, 1, o, {1.0}, {1.0}), InputError);
}

}  // namespace
}  // namespace prtsub
