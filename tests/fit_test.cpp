#include "prtsub/prt/fit.h"
#include "prtsub/prt/unshadowed_projection.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cstdio>
#include <functional>

#include "helpers.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/sh.h"

namespace prtsub {
namespace {

// The estimator itself, as the paper states it: these tests check its mathematics on signals
// that may be negative, so the transfer-only limit (non_negative) is off. (The noise weighting
// needs vertex variances, which these calls do not pass.)
FitOptions plain_fit() {
  FitOptions o;
  o.non_negative = NonNegative::Off;
  return o;
}

using Signal = std::function<double(const Eigen::Vector3d&)>;

RowMatrixXd at_vertices(const Mesh& m, const Signal& f) {
  RowMatrixXd v(Eigen::Index(m.num_vertices()), 1);
  for (uint32_t i = 0; i < m.num_vertices(); ++i) v(i, 0) = f(m.point(i));
  return v;
}

RowMatrixXd at_samples(const SurfaceSamples& s, const Signal& f) {
  RowMatrixXd v(Eigen::Index(s.size()), 1);
  for (Eigen::Index i = 0; i < v.rows(); ++i) v(i, 0) = f(s.points.row(i).transpose());
  return v;
}

// ∫ over each face of F(p, barycentrics) by a Duffy-mapped 12×12 Gauss-Legendre rule:
// an independent quadrature, not the samples under test.
double integrate(const Mesh& m, const std::function<double(uint32_t, const Eigen::Vector3d&, const Eigen::Vector3d&)>& F) {
  std::vector<double> x, w;
  test::gauss_legendre(12, x, w);
  double total = 0;
  for (uint32_t f = 0; f < m.num_faces(); ++f) {
    const Triangle& t = m.triangles[f];
    const double area = triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2]));
    for (size_t i = 0; i < x.size(); ++i)
      for (size_t j = 0; j < x.size(); ++j) {
        const double s = 0.5 * (x[i] + 1), r = 0.5 * (x[j] + 1);
        const double u = s, v = (1 - s) * r, jac = (1 - s) * 0.25 * w[i] * w[j];
        const Eigen::Vector3d b(1 - u - v, u, v);
        const Eigen::Vector3d p = b[0] * m.point(t[0]) + b[1] * m.point(t[1]) + b[2] * m.point(t[2]);
        total += 2 * area * jac * F(f, p, b);
      }
  }
  return total;
}

// ‖f − g_x‖² over the surface, g_x the linear interpolant of vertex values x.
double l2_error(const Mesh& m, const RowMatrixXd& x, const Signal& f) {
  return integrate(m, [&](uint32_t face, const Eigen::Vector3d& p, const Eigen::Vector3d& b) {
    const Triangle& t = m.triangles[face];
    const double g = b[0] * x(t[0], 0) + b[1] * x(t[1], 0) + b[2] * x(t[2], 0);
    return (f(p) - g) * (f(p) - g);
  });
}

double sigmoid(const Eigen::Vector3d& p) { return 1 / (1 + std::exp(-(p.x() - 0.37) / 0.03)); }

TEST(SurfaceSamples, EveryFaceGetsItsMinimumAndTheRestGoesByArea) {
  Mesh m = test::build(test::grid(6, 0.6));
  SampleOptions o;
  o.per_triangle = 10, o.min_per_triangle = 2;
  SurfaceSamples s = make_surface_samples(m, o);
  EXPECT_EQ(s.size(), 10 * m.num_faces());
  double area_total = 0, weight_total = 0, worst_share = 0;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const Triangle& t = m.triangles[f];
    const double a = triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2]));
    const size_t n = s.begin[f + 1] - s.begin[f];
    EXPECT_GE(n, 2u);
    double wsum = 0;
    for (size_t k = s.begin[f]; k < s.begin[f + 1]; ++k) {
      wsum += s.weight[k];
      EXPECT_EQ(s.face[k], f);
      const Eigen::Vector3d b = s.barycentric.row(Eigen::Index(k)).transpose();
      EXPECT_GE(b.minCoeff(), 0.0);
      EXPECT_NEAR(b.sum(), 1.0, 1e-12);
      const Eigen::Vector3d p = b[0] * m.point(t[0]) + b[1] * m.point(t[1]) + b[2] * m.point(t[2]);
      EXPECT_LT((p - s.points.row(Eigen::Index(k)).transpose()).norm(), 1e-12);
    }
    EXPECT_NEAR(wsum, a, 1e-12);
    area_total += a, weight_total += wsum;
    // Beyond the minimum, a face's share tracks its area to within one sample (systematic sampling).
    const double expected_extra = 8.0 * double(m.num_faces()) * a;
    worst_share = std::max(worst_share, std::abs(double(n - 2) - expected_extra));
  }
  EXPECT_NEAR(weight_total, area_total, 1e-12);
  EXPECT_LE(worst_share, 1.0 + 1e-9);
  // Same seed, same samples; another seed, others.
  SurfaceSamples again = make_surface_samples(m, o);
  EXPECT_EQ(again.points, s.points);
  o.seed = 99;
  EXPECT_NE(make_surface_samples(m, o).points, s.points);
}

TEST(SurfaceSamples, FaceWeightsSteerTheExtraSamplesAndWeightZeroLeavesAFaceToInterpolation) {
  Mesh m = test::build(test::grid(6, 0.6));
  SampleOptions o;
  o.per_triangle = 10, o.min_per_triangle = 1;
  std::vector<double> w(m.num_faces());
  for (size_t f = 0; f < w.size(); ++f) w[f] = f % 3 == 0 ? 0.0 : f % 3 == 1 ? 3.0 : 1.0;
  const SurfaceSamples s = make_surface_samples(m, o, w);
  ASSERT_EQ(s.interpolated.size(), m.num_faces());
  EXPECT_EQ(s.size(), 10 * m.num_faces());
  double share_total = 0;
  size_t weighted_faces = 0;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const Triangle& t = m.triangles[f];
    if (w[f] > 0) share_total += w[f] * triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2])), ++weighted_faces;
  }
  const double extra = double(s.size() - weighted_faces);
  double worst = 0;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const size_t n = s.begin[f + 1] - s.begin[f];
    EXPECT_EQ(s.interpolated[f] != 0, w[f] == 0) << f;
    if (w[f] == 0) {
      EXPECT_EQ(n, 0u);
      continue;
    }
    const Triangle& t = m.triangles[f];
    const double a = triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2]));
    worst = std::max(worst, std::abs(double(n - 1) - extra * w[f] * a / share_total));  // systematic: within one
    double wsum = 0;
    for (size_t k = s.begin[f]; k < s.begin[f + 1]; ++k) wsum += s.weight[k];
    EXPECT_NEAR(wsum, a, 1e-12);
  }
  EXPECT_LE(worst, 1.0 + 1e-9);
  EXPECT_TRUE(make_surface_samples(m, o).interpolated.empty());  // no weights, no interpolated faces
  EXPECT_THROW(make_surface_samples(m, o, std::vector<double>(3, 1.0)), InputError);
  w[1] = -1;
  EXPECT_THROW(make_surface_samples(m, o, w), InputError);
  w[1] = NAN;
  EXPECT_THROW(make_surface_samples(m, o, w), InputError);
}

// Two sample sets merged (the sample rounds of --error): the merged set is what one set with
// both sets' points would be, and the merged moments are the moments computed on it directly.
TEST(SurfaceSamples, TwoSetsMergeIntoOneWhoseMomentsAreTheCountWeightedMean) {
  Mesh m = test::build(test::grid(5, 0.4));
  std::vector<double> w(m.num_faces());
  for (size_t f = 0; f < w.size(); ++f) w[f] = f % 4 == 0 ? 0.0 : 1.0 + double(f % 3);
  SampleOptions o;
  o.per_triangle = 3, o.seed = 1;
  const SurfaceSamples a = make_surface_samples(m, o, w);
  o.per_triangle = 11, o.seed = 2;
  const SurfaceSamples b = make_surface_samples(m, o, w);
  const SurfaceSamples ab = merge_surface_samples(a, b);
  ASSERT_EQ(ab.size(), a.size() + b.size());
  const Signal f = sigmoid;
  const RowMatrixXd va = at_samples(a, f), vb = at_samples(b, f), vab = at_samples(ab, f);
  for (size_t t = 0; t < m.num_faces(); ++t) {
    const size_t na = a.begin[t + 1] - a.begin[t], nb = b.begin[t + 1] - b.begin[t];
    ASSERT_EQ(ab.begin[t + 1] - ab.begin[t], na + nb);
    EXPECT_EQ(ab.interpolated[t] != 0, w[t] == 0) << t;
    double wsum = 0;
    for (size_t k = ab.begin[t]; k < ab.begin[t + 1]; ++k) {
      EXPECT_EQ(ab.face[k], t);
      wsum += ab.weight[k];
    }
    if (na + nb) {
      const Triangle& tr = m.triangles[t];
      EXPECT_NEAR(wsum, triangle_area(m.point(tr[0]), m.point(tr[1]), m.point(tr[2])), 1e-12);
    }
    if (nb) {
      EXPECT_EQ(ab.points.row(Eigen::Index(ab.begin[t] + na)), b.points.row(Eigen::Index(b.begin[t])));  // a's, then b's
    }
  }
  FaceMoments ma = face_moments(m, a, va), mb = face_moments(m, b, vb);
  ma.variance.assign(3 * m.num_faces(), 2.0), mb.variance.assign(3 * m.num_faces(), 1.0);
  const FaceMoments merged = merge_face_moments(a, ma, b, mb), direct = face_moments(m, ab, vab);
  EXPECT_LT((merged.rows - direct.rows).cwiseAbs().maxCoeff(), 1e-12 * direct.rows.cwiseAbs().maxCoeff());
  for (size_t t = 0; t < m.num_faces(); ++t) {
    const double na = double(a.begin[t + 1] - a.begin[t]), nb = double(b.begin[t + 1] - b.begin[t]);
    if (na + nb == 0) continue;
    EXPECT_NEAR(merged.variance[3 * t], (na * na * 2 + nb * nb * 1) / ((na + nb) * (na + nb)), 1e-12) << t;
  }
  SurfaceSamples other = make_surface_samples(test::build(test::grid(3, 0.4)), o);
  EXPECT_THROW(merge_surface_samples(a, other), InputError);
  EXPECT_THROW(merge_face_moments(a, ma, other, mb), InputError);
}

TEST(SurfaceSamples, DensityModeAndZeroAreaFaces) {
  RawMesh r = test::grid(4, 0);
  // A zero-area face (three collinear points) beside the grid.
  const Eigen::Index base = r.positions.rows();
  r.positions.conservativeResize(base + 3, 3);
  r.positions.row(base) << 2, 0, 0;
  r.positions.row(base + 1) << 3, 0, 0;
  r.positions.row(base + 2) << 4, 0, 0;
  r.face_indices.insert(r.face_indices.end(), {base, base + 1, base + 2});
  r.face_offsets.push_back(r.face_indices.size());
  Mesh m = test::build(r);
  SampleOptions o;
  o.density = 1000, o.min_per_triangle = 1;
  SurfaceSamples s = make_surface_samples(m, o);
  EXPECT_EQ(s.size(), 1000u);  // density × unit area
  const size_t last = m.num_faces() - 1;
  EXPECT_EQ(s.begin[last + 1] - s.begin[last], 0u);
}

TEST(SurfaceSamples, EachSampleIsUniformOnItsFace) {
  // The mean of x² over all samples estimates ∫x²/area = 1/3 on the unit square without bias;
  // with the lattice the error is far below the iid standard error, which bounds it here.
  Mesh m = test::build(test::grid(3, 0.5));
  SampleOptions o;
  o.per_triangle = 50;
  double worst = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    o.seed = seed;
    SurfaceSamples s = make_surface_samples(m, o);
    double est = 0;
    for (size_t k = 0; k < s.size(); ++k) est += s.weight[k] * s.points(Eigen::Index(k), 0) * s.points(Eigen::Index(k), 0);
    worst = std::max(worst, std::abs(est - 1.0 / 3));
  }
  const double iid_sigma = std::sqrt((1.0 / 5 - 1.0 / 9) / (50.0 * 18));  // Var(x²) on [0,1]², over 900 samples
  EXPECT_LT(worst, 3 * iid_sigma);
}

TEST(FitMatrices, AnalyticMassIntegratesPiecewiseLinearProductsExactly) {
  Mesh m = test::build(test::grid(5, 0.5));
  SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  const SparseMatrixd A = mass_matrix(m, s, MassMatrix::Analytic);
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(A.rows());
  EXPECT_NEAR(one.dot(A * one), 1.0, 1e-12);  // total area
  Eigen::VectorXd x(A.rows()), y(A.rows());
  for (uint32_t i = 0; i < m.num_vertices(); ++i) x[i] = m.point(i).x(), y[i] = 1 + 2 * m.point(i).y();
  EXPECT_NEAR(x.dot(A * x), 1.0 / 3, 1e-12);     // ∫x²
  EXPECT_NEAR(x.dot(A * y), 0.5 * 2.0, 1e-12);   // ∫x(1+2y) = 1/2 + 2·1/4
  // The sampled matrix estimates the same integrals.
  SampleOptions many;
  many.per_triangle = 400;
  const SparseMatrixd As = mass_matrix(m, make_surface_samples(m, many), MassMatrix::Sampled);
  EXPECT_NEAR(one.dot(As * one), 1.0, 1e-12);  // Σ weights = area, exactly
  EXPECT_NEAR(x.dot(As * x), 1.0 / 3, 2e-3);
}

TEST(FitMatrices, GradientRegularizerIsAreaScaledDirichletEnergy) {
  const int n = 6;
  Mesh m = test::build(test::grid(n, 0));
  const SparseMatrixd R = gradient_regularizer(m);
  Eigen::VectorXd one = Eigen::VectorXd::Ones(R.rows()), x(R.rows());
  EXPECT_LT((R * one).norm(), 1e-12);
  for (uint32_t i = 0; i < m.num_vertices(); ++i) x[i] = 3 * m.point(i).x() - m.point(i).y();
  // Σ_t a_t² |∇g|²: 2n² faces of area 1/(2n²), |∇g|² = 10.
  EXPECT_NEAR(x.dot(R * x), 10.0 / (2.0 * n * n), 1e-12);
  EXPECT_LT((Eigen::MatrixXd(R) - Eigen::MatrixXd(R).transpose()).norm(), 1e-15);
}

TEST(FitMatrices, EdgeRegularizerIgnoresLinearFunctionsAndCreases) {
  Mesh m = test::build(test::grid(5, 0.5));
  size_t interior = 0;
  const SparseMatrixd R = edge_regularizer(m, &interior);
  EXPECT_EQ(interior, 3u * 5 * 5 - 2 * 5);  // every edge not on the square's boundary
  Eigen::VectorXd x(R.rows()), tent = Eigen::VectorXd::Zero(R.rows());
  for (uint32_t i = 0; i < m.num_vertices(); ++i) x[i] = 2 + 3 * m.point(i).x() - m.point(i).y();
  tent[14] = 1;  // an interior vertex: a hat has gradient jumps on every edge around it
  EXPECT_GT(tent.dot(R * tent), 0.1);
  EXPECT_LT(x.dot(R * x), 1e-13 * x.squaredNorm() * tent.dot(R * tent));  // rounding only
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(R)};
  EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-12);  // positive semi-definite

  // A cube: every cube edge is a crease (90° > 60°), so only the face diagonals are interior.
  Mesh cube = test::build(test::cube());
  edge_regularizer(cube, &interior);
  EXPECT_EQ(interior, 6u);
  // Folded but smooth (crease angle 120°): a function linear on the unfolded strip still costs nothing.
  Mesh folded = test::build(test::cube(), 120);
  const SparseMatrixd Rf = edge_regularizer(folded, &interior);
  EXPECT_EQ(interior, 18u);
  Eigen::VectorXd c = Eigen::VectorXd::Constant(Rf.rows(), 0.7);
  EXPECT_LT(c.dot(Rf * c), 1e-14);
}

struct FitRun {
  RowMatrixXd point, average, lsq, lsq_alpha;
};

FitRun run_fits(const Mesh& m, const Signal& f, const SampleOptions& so, double alpha = 0.1) {
  SurfaceSamples s = make_surface_samples(m, so);
  const RowMatrixXd values = at_samples(s, f);
  FitRun r;
  r.point = at_vertices(m, f);
  FitOptions o = plain_fit();
  o.method = FitMethod::Average;
  r.average = fit_vertex_values(m, s, values, r.point, o);
  o.method = FitMethod::LeastSquares;
  o.alpha = 0;
  r.lsq = fit_vertex_values(m, s, values, r.point, o);
  o.alpha = alpha;
  r.lsq_alpha = fit_vertex_values(m, s, values, r.point, o);
  return r;
}

TEST(Fit, LeastSquaresBeatsAverageBeatsPointOnAShadowEdge) {
  Mesh m = test::build(test::grid(8, 0.5));
  SampleOptions so;
  so.per_triangle = 64;  // dense, as the paper's E_lsq: with few samples α = 0 fits the noise
  FitRun r = run_fits(m, sigmoid, so);
  const double e_point = l2_error(m, r.point, sigmoid), e_avg = l2_error(m, r.average, sigmoid),
               e_lsq = l2_error(m, r.lsq, sigmoid), e_alpha = l2_error(m, r.lsq_alpha, sigmoid);
  // The exact L2 projection, from the independent quadrature: the lowest error any vertex values reach.
  SurfaceSamples s = make_surface_samples(m, so);
  Eigen::MatrixXd A(mass_matrix(m, s, MassMatrix::Analytic));
  Eigen::VectorXd b = Eigen::VectorXd::Zero(A.rows());
  for (int i = 0; i < A.rows(); ++i)
    b[i] = integrate(m, [&](uint32_t face, const Eigen::Vector3d& p, const Eigen::Vector3d& w) {
      const Triangle& t = m.triangles[face];
      for (int c = 0; c < 3; ++c)
        if (int(t[c]) == i) return w[c] * sigmoid(p);
      return 0.0;
    });
  RowMatrixXd proj = A.ldlt().solve(b);
  const double e_proj = l2_error(m, proj, sigmoid);
  EXPECT_LT(e_lsq, 0.8 * e_avg);
  EXPECT_LT(e_lsq, 0.8 * e_point);
  EXPECT_LE(e_lsq, e_alpha);
  EXPECT_LT(e_alpha, e_avg);
  // (A noiseless f favours point sampling, which interpolates it exactly at the vertices;
  // E_avg <= E_point is a claim about noisy signals, measured on real scenes in BENCHMARKS.md.)
  // Optimality: plain lsq's excess over the projection is δbᵀA⁻¹δb, δb the Monte Carlo error of b;
  // its mean is trace(A⁻¹C), C the covariance of b over sample seeds. Estimate C from 24 other
  // seeds and hold this seed's excess to 4× that mean (a sum of many squared terms rarely
  // exceeds its mean by 4×, and a wrong solve misses by orders of magnitude more).
  EXPECT_GE(e_lsq, e_proj * (1 - 1e-9));
  const int seeds = 24;
  Eigen::MatrixXd bs(A.rows(), seeds);
  for (int k = 0; k < seeds; ++k) {
    SampleOptions other = so;
    other.seed = 1000 + uint64_t(k);
    SurfaceSamples sk = make_surface_samples(m, other);
    bs.col(k) = Eigen::MatrixXd(fit_right_hand_side(m, sk, at_samples(sk, sigmoid)));
  }
  const Eigen::MatrixXd centred = bs.colwise() - bs.rowwise().mean();
  const Eigen::MatrixXd C = centred * centred.transpose() / (seeds - 1);
  const double mean_excess = (A.ldlt().solve(C)).trace();
  // That theory is for the plain estimate of b; the control variate (the default) estimates only
  // ∫h_i (f − g_prior), and must do far better.
  FitOptions plain = plain_fit();
  plain.alpha = 0, plain.control_variate = false;
  const RowMatrixXd x_plain = fit_vertex_values(m, s, at_samples(s, sigmoid), r.point, plain);
  const double e_plain = l2_error(m, x_plain, sigmoid);
  EXPECT_LT(e_plain - e_proj, 4 * mean_excess);
  EXPECT_GT(e_plain - e_proj, 0.05 * mean_excess);  // the theory is not vacuous
  EXPECT_LT(e_lsq - e_proj, 0.1 * mean_excess);
  std::printf("E_point %.3g  E_avg %.3g  E(0.1) %.3g  E_lsq %.3g  E_proj %.3g  (excess: plain %.2g, expected %.2g; "
              "control variate %.2g)\n", e_point, e_avg, e_alpha, e_lsq, e_proj, e_plain - e_proj, mean_excess, e_lsq - e_proj);
}

TEST(Fit, SampledMassAndEdgeRegularizerReproduceLinearSignalsExactly) {
  // With the sampled mass matrix the fit is discrete least squares on the samples: a linear f
  // is interpolated exactly by its own vertex values, and R_edge does not object to it.
  Mesh m = test::build(test::grid(6, 0.5));
  const Signal f = [](const Eigen::Vector3d& p) { return 0.3 + 2 * p.x() - 5 * p.y(); };
  SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  FitOptions o = plain_fit();
  o.mass = MassMatrix::Sampled, o.alpha = 0.1;
  const RowMatrixXd prior = RowMatrixXd::Zero(Eigen::Index(m.num_vertices()), 1);
  FitStats st;
  RowMatrixXd x = fit_vertex_values(m, s, at_samples(s, f), prior, o, &st);
  EXPECT_LT((x - at_vertices(m, f)).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(st.stabilizer, 0.0);
  EXPECT_EQ(st.unsupported, 0u);
}

TEST(Fit, TheAssemblysPartsAreTimedWithinItsTotal) {
  // The report splits seconds_assemble into the face sums, the edge blocks and the rows: each
  // part is recorded (a pass over 1280 faces takes some time) and together they fit in the total.
  Mesh m = test::build(test::icosphere(3));
  SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  const Signal f = [](const Eigen::Vector3d& p) { return std::sin(3 * p.x()) + p.y() * p.z(); };
  FitOptions o = plain_fit();
  o.alpha = 0.1;
  FitStats st;
  fit_vertex_values(m, s, at_samples(s, f), RowMatrixXd::Zero(Eigen::Index(m.num_vertices()), 1), o, &st);
  EXPECT_GT(st.seconds_assemble_sums, 0.0);
  EXPECT_GT(st.seconds_assemble_edges, 0.0);
  EXPECT_GT(st.seconds_assemble_rows, 0.0);
  EXPECT_LE(st.seconds_assemble_sums + st.seconds_assemble_edges + st.seconds_assemble_rows, st.seconds_assemble);
}

TEST(Fit, ManyRightHandSidesMatchADenseSolveColumnByColumn) {
  // Order 10: 100 right-hand sides through one factorisation.
  Mesh m = test::build(test::icosphere(1));
  SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  RowMatrixXd values(Eigen::Index(s.size()), 100);
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (int k = 0; k < 100; ++k) values(i, k) = std::sin(k * s.points(i, 0) + 0.1 * k) + s.points(i, 2) * k;
  const RowMatrixXd prior = RowMatrixXd::Zero(Eigen::Index(m.num_vertices()), 100);
  FitOptions o = plain_fit();
  o.alpha = 0.1;  // CG stopped at a relative residual of 1e-12: at α = 0.1 this system's condition keeps the error under 1e-10
  o.cg_tolerance = 1e-12;
  RowMatrixXd x = fit_vertex_values(m, s, values, prior, o);
  Eigen::MatrixXd M = Eigen::MatrixXd(mass_matrix(m, s, MassMatrix::Analytic)) + o.alpha * Eigen::MatrixXd(edge_regularizer(m));
  Eigen::MatrixXd b = fit_right_hand_side(m, s, values);
  Eigen::MatrixXd dense = M.llt().solve(b);
  EXPECT_LT((Eigen::MatrixXd(x) - dense).cwiseAbs().maxCoeff(), 1e-10 * dense.cwiseAbs().maxCoeff());
}

TEST(Fit, ConjugateGradientsAgreeWithCholmodAndFallBackWhenTheyStall) {
  // Order 4 on a jittered sphere, both regularisers and α = 0: the iterative solve (the default
  // with the analytic mass) and the factorisation solve the same system.
  Mesh m = test::build(test::icosphere(2));
  SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  RowMatrixXd values(Eigen::Index(s.size()), 16), prior(Eigen::Index(m.num_vertices()), 16);
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (int k = 0; k < 16; ++k) values(i, k) = std::cos(k * s.points(i, 1)) + (s.points(i, 0) > 0.3 ? 1 : 0);
  for (Eigen::Index i = 0; i < prior.rows(); ++i)
    for (int k = 0; k < 16; ++k) prior(i, k) = std::cos(k * m.point(uint32_t(i)).y());
  int jacobi = 0, blocked = 0, whole = 0;  // how each system was solved
  for (Regularizer reg : {Regularizer::Edge, Regularizer::Gradient})
    for (double alpha : {0.0, 0.1, 1.0, 10.0, 1000.0}) {
      FitOptions o = plain_fit();
      o.regularizer = reg, o.alpha = alpha, o.cg_tolerance = 1e-10;
      FitStats cg_stats, direct_stats;
      const RowMatrixXd cg = fit_vertex_values(m, s, values, prior, o, &cg_stats);
      o.solver = FitSolver::Cholmod;
      const RowMatrixXd direct = fit_vertex_values(m, s, values, prior, o, &direct_stats);
      // A large α makes the regulariser dominate rows' diagonals (stiff rows). A few: CG solves
      // their block directly in each iteration. Every row (α ≥ 1 with the edge regulariser): the
      // block is the whole system, dearer to factor than the system is large, so CHOLMOD's
      // analysis of the whole decides, before any iteration (its factor is small here). Measured:
      // gradient α = 1 has 12 stiff rows (17 iterations); α ≥ 10, and edge α ≥ 1, all rows.
      const std::string what = std::string(regularizer_name(reg)) + " alpha " + std::to_string(alpha);
      if (cg_stats.stiff_share == 0) {
        ++jacobi;
        EXPECT_EQ(cg_stats.solver, "cg") << what;
        EXPECT_EQ(cg_stats.stiff_rows, 0u) << what;
      } else if (cg_stats.stiff_rows > 0) {
        ++blocked;
        EXPECT_EQ(cg_stats.solver, "cg") << what;
        EXPECT_EQ(double(cg_stats.stiff_rows), cg_stats.stiff_share * double(m.num_vertices())) << what;
        EXPECT_GT(cg_stats.stiff_factor_entries, 0u) << what;
        EXPECT_LE(cg_stats.stiff_factor_entries, cg_stats.system_nonzeros) << what;
      } else {
        ++whole;
        EXPECT_EQ(cg_stats.solver, "cholmod") << what;
        EXPECT_EQ(cg_stats.cg_iterations, 0) << what;
        EXPECT_GT(cg_stats.predicted_factor_entries, cg_stats.system_nonzeros) << what;
      }
      if (cg_stats.solver == "cg") {
        EXPECT_GT(cg_stats.cg_iterations, 0) << what;
        EXPECT_LT(cg_stats.cg_iterations, 100) << what;
      }
      EXPECT_EQ(direct_stats.solver, "cholmod");
      EXPECT_GT(direct_stats.factor_nonzeros, 0u);
      EXPECT_TRUE(cg_stats.warning.empty());
      EXPECT_LT((cg - direct).cwiseAbs().maxCoeff(), 1e-8 * direct.cwiseAbs().maxCoeff())
          << regularizer_name(reg) << " alpha " << alpha;
    }
  EXPECT_EQ(jacobi, 4);
  EXPECT_EQ(blocked, 1);
  EXPECT_EQ(whole, 5);
  // Too few iterations allowed: CHOLMOD takes over, the stats say so, and it gives its own answer.
  FitOptions o = plain_fit();
  o.cg_max_iterations = 2;
  FitStats st;
  const RowMatrixXd x = fit_vertex_values(m, s, values, prior, o, &st);
  EXPECT_EQ(st.solver, "cholmod");
  EXPECT_EQ(st.cg_iterations, 2);
  EXPECT_TRUE(st.warning.empty()) << st.warning;  // normal operation for a stiff system
  o.solver = FitSolver::Cholmod;
  EXPECT_EQ(x, fit_vertex_values(m, s, values, prior, o));
  // The sampled mass matrix can be singular: it always goes to CHOLMOD and its condition check.
  o.solver = FitSolver::Auto, o.mass = MassMatrix::Sampled;
  fit_vertex_values(m, s, values, prior, o, &st);
  EXPECT_EQ(st.solver, "cholmod");
  EXPECT_EQ(st.cg_iterations, 0);
}

TEST(Fit, TheMultigridPreconditionerAgreesWithCholmodInFewerIterations) {
  // A fine jittered grid with a strong regulariser (its smooth functions are barely penalised
  // next to the small faces' mass: CG's hard case), also a million units from the origin (the
  // near-null vectors are built from centred positions): the multigrid-preconditioned CG and
  // CHOLMOD solve the same system, and the cycle needs far fewer iterations than Jacobi's CG.
  for (double offset : {0.0, 1e6}) {
    const Mesh m = test::build(test::transformed(test::grid(96, 0.3), 1.0, Eigen::Vector3d(offset, -offset, offset)));
    const SurfaceSamples s = make_surface_samples(m, SampleOptions{});
    const Eigen::Vector3d centre = m.point(0);
    const Signal f = [&](const Eigen::Vector3d& p) { return std::sin(9 * (p - centre).x()) * std::cos(7 * (p - centre).y()); };
    const RowMatrixXd prior = at_vertices(m, f) * 0.5;
    FitOptions o = plain_fit();
    o.alpha = 10.0, o.cg_tolerance = 1e-10, o.cg_max_iterations = 2000;
    FitStats st[3];
    RowMatrixXd x[3];
    const FitSolver solvers[3] = {FitSolver::Cg, FitSolver::Multigrid, FitSolver::Cholmod};
    for (int k = 0; k < 3; ++k) {
      o.solver = solvers[k];
      x[k] = fit_vertex_values(m, s, at_samples(s, f), prior, o, &st[k]);
    }
    EXPECT_EQ(st[0].solver, "cg");
    EXPECT_EQ(st[1].solver, "cg-multigrid");
    EXPECT_EQ(st[2].solver, "cholmod");
    EXPECT_GE(st[1].multigrid_levels, 2);
    // Measured: 153 iterations against 30 (two levels, operator complexity 1.78), at both offsets.
    std::printf("offset %g: CG %d iterations, multigrid %d (%d levels, operator complexity %.2f)\n", offset, st[0].cg_iterations,
                st[1].cg_iterations, st[1].multigrid_levels, st[1].multigrid_operator_complexity);
    EXPECT_LT(3 * st[1].cg_iterations, st[0].cg_iterations) << "offset " << offset;
    for (int k = 0; k < 2; ++k)
      EXPECT_LT((x[k] - x[2]).cwiseAbs().maxCoeff(), 1e-7 * x[2].cwiseAbs().maxCoeff()) << k << " offset " << offset;
  }
}

TEST(Fit, FacesLeftToInterpolationHoldTheirVerticesAtThePrior) {
  // Interpolated faces say "the prior is right here": a vertex with no sampled face keeps its
  // prior exactly (even a wrong one), and where the prior is the exact linear signal the fit
  // reproduces it with any mix of sampled and interpolated faces.
  const Mesh m = test::build(test::grid(6, 0.5));
  const Signal f = [](const Eigen::Vector3d& p) { return 0.3 + 2 * p.x() - 5 * p.y(); };
  SampleOptions so;
  std::vector<double> w(m.num_faces(), 1.0);
  for (size_t k = 0; k < m.num_faces(); ++k) {  // faces left of x = 0.5 to interpolation
    const Triangle& t = m.triangles[k];
    if ((m.point(t[0]) + m.point(t[1]) + m.point(t[2])).x() / 3 < 0.5) w[k] = 0;
  }
  const SurfaceSamples s = make_surface_samples(m, so, w);
  for (MassMatrix mass : {MassMatrix::Analytic, MassMatrix::Sampled}) {
    FitOptions o = plain_fit();
    o.mass = mass;
    const RowMatrixXd exact = at_vertices(m, f);
    EXPECT_LT((fit_vertex_values(m, s, at_samples(s, f), exact, o) - exact).cwiseAbs().maxCoeff(), 1e-9) << mass_matrix_name(mass);
    // A wrong prior: vertices whose faces are all interpolated keep it, the others move to f.
    RowMatrixXd wrong = exact;
    wrong.array() += 0.5;
    FitStats st;
    const RowMatrixXd x = fit_vertex_values(m, s, at_samples(s, f), wrong, o, &st);
    size_t held = 0;
    for (uint32_t i = 0; i < m.num_vertices(); ++i) {
      bool sampled = false;
      for (size_t k = 0; k < m.num_faces(); ++k)
        for (int c = 0; c < 3; ++c) sampled |= m.triangles[k][c] == i && w[k] > 0;
      if (!sampled) {
        EXPECT_EQ(x(i, 0), wrong(i, 0));
        ++held;
      } else if (m.point(i).x() > 0.7) {
        EXPECT_NEAR(x(i, 0), exact(i, 0), 0.05) << i;  // far from the interpolated side
      }
    }
    EXPECT_GT(held, 10u);
    EXPECT_EQ(st.unsupported, held);
  }
  // Every face interpolated: the prior, untouched.
  const SurfaceSamples none = make_surface_samples(m, so, std::vector<double>(m.num_faces(), 0.0));
  const RowMatrixXd prior = at_vertices(m, sigmoid);
  EXPECT_EQ(none.size(), 0u);
  EXPECT_EQ(fit_vertex_values(m, none, RowMatrixXd(0, 1), prior, plain_fit()), prior);
}

TEST(Fit, TheSystemIsTheSameForAnyThreadCountAndIsTheSumOfItsTerms) {
  // Assembled row by row in breadth-first order with sampled, interpolated and unsampled faces,
  // both regularisers: bit for bit the same for 1, 2 and 3 threads, and entry by entry the mass
  // matrix plus α times the regulariser built independently, face by face, from triplets.
  Mesh m = test::build(test::icosphere(3));
  std::vector<double> w(m.num_faces(), 1.0);
  for (size_t k = 0; k < m.num_faces(); ++k) {
    const Eigen::Vector3d c = (m.point(m.triangles[k][0]) + m.point(m.triangles[k][1]) + m.point(m.triangles[k][2])) / 3;
    if (c.x() > 0.4 || c.z() > 0.7) w[k] = 0;  // left to interpolation
  }
  SurfaceSamples s = make_surface_samples(m, SampleOptions{}, w);
  for (size_t k = 0; k < m.num_faces(); ++k) {  // a cap with no samples and no interpolation either
    const Eigen::Vector3d c = (m.point(m.triangles[k][0]) + m.point(m.triangles[k][1]) + m.point(m.triangles[k][2])) / 3;
    if (c.z() > 0.7) s.interpolated[k] = 0;
  }
  RowMatrixXd values(Eigen::Index(s.size()), 9), prior(Eigen::Index(m.num_vertices()), 9);
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (int k = 0; k < 9; ++k) values(i, k) = std::sin(3 * k * s.points(i, 0)) + s.points(i, 2);
  for (Eigen::Index i = 0; i < prior.rows(); ++i)
    for (int k = 0; k < 9; ++k) prior(i, k) = std::cos(k * m.point(uint32_t(i)).y());
  const FaceMoments moments = face_moments(m, s, values);
  for (Regularizer reg : {Regularizer::Edge, Regularizer::Gradient}) {
    FitOptions o = plain_fit();
    o.regularizer = reg, o.alpha = 0.3, o.threads = 1;
    const FitSystem one = assemble_fit_system(m, s, moments, prior, o);
    for (int threads : {2, 3}) {
      o.threads = threads;
      const FitSystem many = assemble_fit_system(m, s, moments, prior, o);
      EXPECT_EQ(many.slot, one.slot);
      EXPECT_EQ(Eigen::MatrixXd(many.matrix), Eigen::MatrixXd(one.matrix)) << threads << " threads";
      EXPECT_EQ(many.rhs, one.rhs) << threads << " threads";
      EXPECT_EQ(many.scale, one.scale);
    }
    const Eigen::MatrixXd terms = Eigen::MatrixXd(mass_matrix(m, s, MassMatrix::Analytic)) +
                                  o.alpha * Eigen::MatrixXd(reg == Regularizer::Edge ? edge_regularizer(m) : gradient_regularizer(m));
    const Eigen::MatrixXd M(one.matrix);
    size_t free = 0;
    double worst = 0;
    for (uint32_t i = 0; i < m.num_vertices(); ++i) {
      const Eigen::Index si = one.slot[i];
      if (si < 0) continue;
      ++free;
      for (uint32_t j = 0; j < m.num_vertices(); ++j) {
        const Eigen::Index sj = one.slot[j];
        const double assembled = sj < 0 ? 0.0 : M(si, sj) / (one.scale[si] * one.scale[sj]);
        if (sj >= 0) worst = std::max(worst, std::abs(assembled - terms(i, j)));
      }
    }
    EXPECT_LT(worst, 1e-14 * terms.cwiseAbs().maxCoeff()) << regularizer_name(reg);
    EXPECT_GT(free, m.num_vertices() / 2);
    EXPECT_LT(free, m.num_vertices());  // the unsampled cap is fixed at its prior
  }
}

TEST(FitStability, SliversBelowOneHundredthOfADegree) {
  // Pull one interior grid vertex to within 1e-6 of a grid line: faces with angles ~1e-4°.
  RawMesh r = test::grid(6, 0);
  r.positions(3 * 7 + 3, 1) = r.positions(2 * 7 + 3, 1) + 1e-6;
  Mesh m = test::build(r);
  double min_angle = 180;
  for (const Triangle& t : m.triangles)
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d u = m.point(t[(c + 1) % 3]) - m.point(t[c]), v = m.point(t[(c + 2) % 3]) - m.point(t[c]);
      min_angle = std::min(min_angle, std::atan2(u.cross(v).norm(), u.dot(v)) * 180 / M_PI);
    }
  ASSERT_LT(min_angle, 0.01);
  const Signal lin = [](const Eigen::Vector3d& p) { return 1 + p.x() + 2 * p.y(); };
  SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  for (Regularizer reg : {Regularizer::Edge, Regularizer::Gradient}) {
    FitOptions o = plain_fit();
    o.mass = MassMatrix::Sampled, o.regularizer = reg, o.alpha = reg == Regularizer::Edge ? 0.1 : 0.0;
    RowMatrixXd x = fit_vertex_values(m, s, at_samples(s, lin), at_vertices(m, lin), o);
    ASSERT_TRUE(x.allFinite());
    EXPECT_LT((x - at_vertices(m, lin)).cwiseAbs().maxCoeff(), 1e-6);
  }
  // A shadow edge over the slivers: every fit stays finite, and the slivers make nothing worse
  // than on the same grid without them (same samples per face, same signal).
  FitRun fr = run_fits(m, sigmoid, SampleOptions{});
  FitRun plain = run_fits(test::build(test::grid(6, 0)), sigmoid, SampleOptions{});
  EXPECT_TRUE(fr.lsq.allFinite() && fr.lsq_alpha.allFinite() && fr.average.allFinite());
  auto overshoot = [](const RowMatrixXd& x) { return std::max(x.maxCoeff() - 1, -x.minCoeff()); };
  EXPECT_LE(overshoot(fr.average), 0.0);  // a weighted average of values in [0, 1]
  EXPECT_LT(overshoot(fr.lsq_alpha), overshoot(plain.lsq_alpha) + 0.05);
  EXPECT_LT(overshoot(fr.lsq), overshoot(plain.lsq) + 0.05);
  const Mesh plain_mesh = test::build(test::grid(6, 0));
  EXPECT_LT(l2_error(m, fr.lsq_alpha, sigmoid), 1.25 * l2_error(plain_mesh, plain.lsq_alpha, sigmoid));
  EXPECT_LT(l2_error(m, fr.average, sigmoid), 1.25 * l2_error(plain_mesh, plain.average, sigmoid));
}

TEST(FitStability, StripsOfSliversStallJacobiButNotTheStiffRowsBlock) {
  // A building's trouble in miniature: a band of slivers across a grid, 22 rows of vertices
  // squashed 1e-3 of a cell apart, so the 21 inside touch slivers only and their diagonals are
  // nearly all regulariser. Jacobi-scaled CG crawls on the band's smooth functions, which the
  // regulariser barely penalises; with the band's block solved directly in each iteration, CG
  // converges as on a plain grid, to CHOLMOD's answer.
  const int n = 64;
  RawMesh r = test::grid(n, 0);
  for (int j = 21; j < 43; ++j)
    for (int i = 0; i <= n; ++i) r.positions(j * (n + 1) + i, 1) = r.positions(20 * (n + 1) + i, 1) + (j - 20) * 1e-3 / n;
  const Mesh m = test::build(r);
  const SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  const RowMatrixXd values = at_samples(s, sigmoid), prior = at_vertices(m, sigmoid);
  FitOptions o = plain_fit();
  o.weigh_by_noise = false, o.cg_tolerance = 1e-10, o.cg_max_iterations = 5000;
  FitStats st, direct_st;
  const RowMatrixXd x = fit_vertex_values(m, s, values, prior, o, &st);
  o.solver = FitSolver::Cholmod;
  const RowMatrixXd direct = fit_vertex_values(m, s, values, prior, o, &direct_st);
  EXPECT_EQ(st.solver, "cg");
  EXPECT_GE(st.stiff_rows, size_t(21 * (n + 1)));  // at least the band's inside rows
  EXPECT_LE(st.stiff_rows, size_t(23 * (n + 1)));
  EXPECT_LT((x - direct).cwiseAbs().maxCoeff(), 1e-7 * direct.cwiseAbs().maxCoeff());
  // Jacobi alone on the same system, from the same start.
  o.solver = FitSolver::Auto;
  const FitSystem sys = assemble_fit_system(m, s, face_moments(m, s, values), prior, o);
  RowMatrixXd y(sys.matrix.rows(), prior.cols());
  for (size_t i = 0; i < sys.slot.size(); ++i)
    if (sys.slot[i] >= 0) y.row(sys.slot[i]) = prior.row(Eigen::Index(i)) / sys.scale[sys.slot[i]];
  BlockCgOptions co;
  co.tolerance = 1e-10, co.max_iterations = 5000, co.predict_stall = false;
  const BlockCgResult jacobi = block_conjugate_gradient(sys.matrix, sys.rhs, y, co);
  std::printf("stiff rows %zu: Jacobi %d iterations, the block %d\n", st.stiff_rows, jacobi.iterations, st.cg_iterations);
  // Measured: 1495 stiff rows; Jacobi 121 iterations, the block 12.
  EXPECT_GT(jacobi.iterations, 5 * st.cg_iterations);
}

TEST(FitStability, NearZeroAreaTrianglesIsolatedAndUnsampledVertices) {
  RawMesh r = test::grid(5, 0.4);
  const Eigen::Index base = r.positions.rows();
  // A separate triangle of relative area 1e-22 (no samples, no gradient), one of ordinary area
  // that the density below leaves without samples, and an isolated vertex.
  r.positions.conservativeResize(base + 7, 3);
  r.positions.row(base + 0) << 3, 0, 0;
  r.positions.row(base + 1) << 4, 0, 0;
  r.positions.row(base + 2) << 3.5, 1e-22, 0;
  r.positions.row(base + 3) << 5, 0, 0;
  r.positions.row(base + 4) << 5.001, 0, 0;
  r.positions.row(base + 5) << 5, 0.001, 0;
  r.positions.row(base + 6) << 9, 9, 9;
  for (Eigen::Index k : {base, base + 3}) {
    r.face_indices.insert(r.face_indices.end(), {k, k + 1, k + 2});
    r.face_offsets.push_back(r.face_indices.size());
  }
  Mesh m = test::build(r);
  // The loader drops unreferenced vertices; add one back by hand as a caller of the library could.
  m.vertex_position.push_back(0);
  m.normals.conservativeResize(m.normals.rows() + 1, 3);
  m.normals.row(m.normals.rows() - 1) << 0, 0, 1;
  SampleOptions so;
  so.density = 400, so.min_per_triangle = 0;
  SurfaceSamples s = make_surface_samples(m, so);
  const Signal f = sigmoid;
  RowMatrixXd prior = at_vertices(m, f);
  prior.bottomRows(7).setConstant(0.123);
  // The grid alone, with the grid's samples: its values must not feel the parts that hold none.
  const size_t grid_faces = 50;
  Mesh g = m;
  g.triangles.resize(grid_faces), g.source_face.resize(grid_faces);
  SurfaceSamples gs = s;
  ASSERT_EQ(s.begin[m.num_faces()], s.begin[grid_faces]);  // no samples beyond the grid
  gs.begin.resize(grid_faces + 1);
  for (double alpha : {0.0, 0.1}) {
    FitOptions o = plain_fit();
    o.alpha = alpha;
    FitStats st;
    RowMatrixXd x = fit_vertex_values(m, s, at_samples(s, f), prior, o, &st);
    ASSERT_TRUE(x.allFinite());
    EXPECT_EQ(st.unsupported, 7u);  // 3 + 3 + the isolated one keep their prior
    EXPECT_TRUE((x.bottomRows(7).array() == 0.123).all());
    RowMatrixXd xg = fit_vertex_values(g, gs, at_samples(gs, f), prior, o);
    EXPECT_LT((x - xg).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(FitStability, TranslationAndScaleDoNotChangeTheResult) {
  RawMesh r = test::grid(6, 0.5);
  Mesh m = test::build(r);
  SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  const RowMatrixXd values = at_samples(s, sigmoid), prior = at_vertices(m, sigmoid);
  for (Regularizer reg : {Regularizer::Edge, Regularizer::Gradient}) {
    FitOptions o = plain_fit();
    o.regularizer = reg;
    const RowMatrixXd x = fit_vertex_values(m, s, values, prior, o);
    for (auto [scale, offset] : {std::pair{1.0, 1e6}, std::pair{1e-4, 0.0}}) {
      Mesh t = test::build(test::transformed(r, scale, Eigen::Vector3d(offset, -offset, 0.5 * offset)));
      SurfaceSamples st = make_surface_samples(t, SampleOptions{});
      ASSERT_EQ(st.size(), s.size());
      EXPECT_LT((st.barycentric - s.barycentric).cwiseAbs().maxCoeff(), 1e-6);
      // The same values at the same (relative) places: the same vertex values.
      const RowMatrixXd y = fit_vertex_values(t, st, values, prior, o);
      EXPECT_LT((x - y).cwiseAbs().maxCoeff(), 1e-6) << "scale " << scale << " offset " << offset;
    }
  }
}

TEST(FitStability, SingularMassMatrixFallsBackToThePointValues) {
  // A strip of 10 triangles has 12 vertices; one sample each gives a sampled mass matrix of
  // rank 10 at most. With α = 0 the system is singular: the fit must say so and stay finite.
  RawMesh r;
  r.positions.resize(12, 3);
  for (int i = 0; i < 6; ++i) r.positions.row(2 * i) << i, 0, 0, r.positions.row(2 * i + 1) << i, 1, 0;
  r.face_offsets.push_back(0);
  for (int64_t i = 0; i < 5; ++i) {
    r.face_indices.insert(r.face_indices.end(), {2 * i, 2 * i + 2, 2 * i + 3, 2 * i, 2 * i + 3, 2 * i + 1});
    r.face_offsets.push_back(r.face_indices.size() - 3);
    r.face_offsets.push_back(r.face_indices.size());
  }
  Mesh m = test::build(r);
  SampleOptions so;
  so.per_triangle = 1;
  SurfaceSamples s = make_surface_samples(m, so);
  ASSERT_EQ(s.size(), 10u);
  const Signal f = [](const Eigen::Vector3d& p) { return std::sin(p.x()) + p.y(); };
  FitOptions o = plain_fit();
  o.mass = MassMatrix::Sampled, o.alpha = 0;
  FitStats st;
  const RowMatrixXd prior = at_vertices(m, f);
  RowMatrixXd x = fit_vertex_values(m, s, at_samples(s, f), prior, o, &st);
  ASSERT_TRUE(x.allFinite());
  EXPECT_GT(st.stabilizer, 0.0);
  EXPECT_NE(st.warning.find("singular"), std::string::npos);
  // The samples are still matched (the pull is tiny), and the null space takes the prior.
  for (size_t k = 0; k < s.size(); ++k) {
    const Triangle& t = m.triangles[s.face[k]];
    double g = 0;
    for (int c = 0; c < 3; ++c) g += s.barycentric(Eigen::Index(k), c) * x(t[c], 0);
    EXPECT_NEAR(g, f(s.points.row(Eigen::Index(k)).transpose()), 1e-4);
  }
  EXPECT_LT((x - prior).cwiseAbs().maxCoeff(), 2.0);
}

TEST(Fit, WithThePilotTheSystemOnTheSampledRegionIsTheWholeMeshs) {
  // A jittered 40 × 40 grid sampled on the faces near its centre only (the rest left to
  // interpolation, as the pilot leaves them): the fit assembles its system on the region around
  // the sampled faces. Against the whole mesh's system, assembled by assemble_fit_system and
  // solved directly, the values agree to round-off, and every vertex outside the region keeps
  // its prior exactly. Edge and gradient regularisers both reach a ring past the unknowns.
  const Mesh g = test::build(test::grid(40, 0.3));
  std::vector<double> weight(g.num_faces(), 0.0);
  size_t sampled = 0;
  for (size_t f = 0; f < g.num_faces(); ++f) {
    const Triangle& t = g.triangles[f];
    const Eigen::Vector3d c = (g.point(t[0]) + g.point(t[1]) + g.point(t[2])) / 3;
    if ((c - Eigen::Vector3d(0.5, 0.5, 0)).norm() < 0.1) weight[f] = 1, ++sampled;
  }
  ASSERT_GT(sampled, 20u);
  ASSERT_LT(sampled * 10, g.num_faces());
  const SurfaceSamples s = make_surface_samples(g, SampleOptions{}, weight);
  ASSERT_EQ(s.interpolated.size(), g.num_faces());
  const Signal f = [](const Eigen::Vector3d& p) { return std::sin(9 * p.x()) * std::cos(7 * p.y()) + std::exp(-50 * (p - Eigen::Vector3d(0.5, 0.5, 0)).squaredNorm()); };
  const FaceMoments moments = face_moments(g, s, at_samples(s, f));
  RowMatrixXd prior = at_vertices(g, f);
  for (Eigen::Index i = 0; i < prior.rows(); ++i) prior(i, 0) += 0.05 * std::sin(37.0 * double(i));  // noise the fit should remove
  for (Regularizer reg : {Regularizer::Edge, Regularizer::Gradient}) {
    FitOptions o = plain_fit();
    o.alpha = 0.05;
    o.regularizer = reg;
    o.cg_tolerance = 1e-13;  // (the default 1e-6 leaves 5e-6 here: the comparison is of systems, not of stopping points)
    const RowMatrixXd x = fit_vertex_values(g, s, moments, prior, o);
    const FitSystem sys = assemble_fit_system(g, s, moments, prior, o);
    const Eigen::SparseMatrix<double> A = sys.matrix;
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
    ASSERT_EQ(ldlt.info(), Eigen::Success);
    const RowMatrixXd y = ldlt.solve(RowMatrixXd(sys.rhs));
    RowMatrixXd ref = prior;
    size_t unknowns = 0;
    for (size_t i = 0; i < g.num_vertices(); ++i)
      if (sys.slot[i] >= 0) ref.row(Eigen::Index(i)) = sys.scale[sys.slot[i]] * y.row(sys.slot[i]), ++unknowns;
    ASSERT_GT(unknowns, 10u);
    EXPECT_LT((x - ref).cwiseAbs().maxCoeff(), 1e-8) << int(reg);
    EXPECT_GT((x - prior).cwiseAbs().maxCoeff(), 1e-3) << int(reg);  // the fit did move the unknowns
    for (size_t i = 0; i < g.num_vertices(); ++i)
      if (sys.slot[i] < 0) {
        EXPECT_EQ(x(Eigen::Index(i), 0), prior(Eigen::Index(i), 0)) << i;
      }
  }
}

TEST(FitStability, BadInputIsAnErrorNotNaN) {
  Mesh m = test::build(test::grid(2, 0.25));
  SurfaceSamples s = make_surface_samples(m, SampleOptions{});
  RowMatrixXd values = RowMatrixXd::Ones(Eigen::Index(s.size()), 1);
  const RowMatrixXd prior = RowMatrixXd::Ones(Eigen::Index(m.num_vertices()), 1);
  FitOptions o = plain_fit();
  o.alpha = -1;
  EXPECT_THROW(fit_vertex_values(m, s, values, prior, o), InputError);
  o.alpha = 0.1;
  for (double share : {-0.1, 1.5, double(NAN)}) {
    o.stiff_mass = share;
    EXPECT_THROW(fit_vertex_values(m, s, values, prior, o), InputError) << share;
  }
  o.stiff_mass = 0.2;
  values(0, 0) = NAN;
  EXPECT_THROW(fit_vertex_values(m, s, values, prior, o), InputError);
  EXPECT_THROW(fit_vertex_values(m, s, RowMatrixXd::Ones(3, 1), prior, o), InputError);
  EXPECT_THROW(parse_fit_method("spline"), InputError);
}

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

// Moments of exact sample values (K columns: f times 1, 2, ..., K) plus seeded Gaussian noise of
// standard deviation sigma in each, with the noise's variance (summed over the K columns) as the
// moments' variance: what trace_face_moments reports.
FaceMoments noisy_moments(const Mesh& m, const SurfaceSamples& s, const Signal& f, double sigma, uint64_t seed, int K = 1) {
  RowMatrixXd values(Eigen::Index(s.size()), K);
  Rng rng(seed, 0);
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (int k = 0; k < K; ++k) {
      const double u1 = std::max(rng.uniform(), 1e-300), u2 = rng.uniform();
      values(i, k) = (k + 1) * f(s.points.row(i).transpose()) + sigma * std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
    }
  FaceMoments moments = face_moments(m, s, values);
  moments.variance.assign(3 * m.num_faces(), 0.0);
  for (size_t k = 0; k < s.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      const double wh = s.weight[k] * s.barycentric(Eigen::Index(k), c);
      moments.variance[3 * s.face[k] + size_t(c)] += wh * wh * sigma * sigma * K;
    }
  return moments;
}

// The same K columns at the vertices, exactly.
RowMatrixXd columns_at_vertices(const Mesh& m, const Signal& f, int K) {
  RowMatrixXd v(Eigen::Index(m.num_vertices()), K);
  for (uint32_t i = 0; i < m.num_vertices(); ++i)
    for (int k = 0; k < K; ++k) v(i, k) = (k + 1) * f(m.point(i));
  return v;
}

TEST(FitNoise, WhereTheCorrectionIsNoiseThePointSamplesStay) {
  // A fine grid and a linear signal in 16 columns (as order-4 transfer has): the point samples
  // hold it exactly (up to their stated, tiny noise), the interpolant has no bias, and the
  // samples are very noisy. The fit's correction is pure noise: weighed by noise, most of it
  // goes. (A positive-part shrinkage keeps a little where a vertex's noisy ‖x − prior‖² happens to
  // look like bias; with 16 columns that is rare.)
  const int K = 16;
  const Mesh m = test::build(test::grid(16, 0.25));
  const Signal f = [](const Eigen::Vector3d& p) { return 0.2 + 0.5 * p.x() - 0.3 * p.y(); };
  SampleOptions so;
  so.per_triangle = 8;
  const SurfaceSamples s = make_surface_samples(m, so);
  const FaceMoments moments = noisy_moments(m, s, f, 0.5, 3, K);
  const RowMatrixXd prior = columns_at_vertices(m, f, K);
  const std::vector<double> prior_variance(m.num_vertices(), 1e-8);
  FitOptions o = plain_fit();
  FitStats plain_stats, weighed_stats;
  const RowMatrixXd plain = fit_vertex_values(m, s, moments, prior, o, &plain_stats);
  const RowMatrixXd weighed = fit_vertex_values(m, s, moments, prior, o, &weighed_stats, &prior_variance);
  const double e_plain = (plain - prior).norm(), e_weighed = (weighed - prior).norm();  // the prior is exact
  EXPECT_GT(e_plain, 1.0);                 // the noise is real
  EXPECT_LT(e_weighed, 0.2 * e_plain);     // and mostly removed (measured: 0.106 of it)
  EXPECT_LT(weighed_stats.kept_correction, 0.1);  // measured: 5.1%
  EXPECT_EQ(plain_stats.kept_correction, 1.0);
  // Without the vertices' variances there is nothing to weigh: the plain fit.
  EXPECT_EQ(fit_vertex_values(m, s, moments, prior, o), plain);
  std::printf("noise only: error %.4g plain, %.4g weighed by noise; %.1f%% of the correction kept\n", e_plain, e_weighed,
              100 * weighed_stats.kept_correction);
}

TEST(FitNoise, WhereTheCorrectionIsSystematicTheFitStays) {
  // A coarse grid and a sharp step inside its faces: point samples miss it, exact samples (no
  // noise: variance 0) see it. The whole correction is kept: the weighed fit is the plain fit.
  const Mesh m = test::build(test::grid(4, 0.25));
  SampleOptions so;
  so.per_triangle = 64;
  const SurfaceSamples s = make_surface_samples(m, so);
  const FaceMoments moments = noisy_moments(m, s, sigmoid, 0.0, 1);
  const RowMatrixXd prior = at_vertices(m, sigmoid);
  const std::vector<double> prior_variance(m.num_vertices(), 1e-4);
  FitOptions o = plain_fit();
  o.alpha = 0;  // the L2 projection: it cannot be further from the signal than the interpolant
  o.weigh_by_noise = false;
  const RowMatrixXd plain = fit_vertex_values(m, s, moments, prior, o);
  o.weigh_by_noise = true;
  FitStats stats;
  const RowMatrixXd weighed = fit_vertex_values(m, s, moments, prior, o, &stats, &prior_variance);
  EXPECT_EQ(stats.kept_correction, 1.0);
  EXPECT_LT((weighed - plain).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(l2_error(m, weighed, sigmoid), 0.8 * l2_error(m, prior, sigmoid));  // and the fit is what helps
}

TEST(FitNonNegative, ConstantKeepsEveryDcCoefficientAtOrAboveZero) {
  // A step from 0 to 1 on a coarse grid: the L2 projection overshoots below 0 beside the step
  // (the hat functions' Gibbs effect), where every point sample is ≥ 0. Constant clamps exactly
  // those DC coefficients and changes nothing else.
  const Mesh m = test::build(test::grid(4, 0.25));
  const Signal step = [](const Eigen::Vector3d& p) { return p.x() > 0.37 ? 1.0 : 0.0; };
  SampleOptions so;
  so.per_triangle = 256;
  const SurfaceSamples s = make_surface_samples(m, so);
  const RowMatrixXd values = at_samples(s, step), prior = at_vertices(m, step);
  FitOptions o = plain_fit();
  o.alpha = 0;
  const RowMatrixXd plain = fit_vertex_values(m, s, values, prior, o);
  const auto negative = (plain.col(0).array() < 0).count();
  ASSERT_GT(negative, 0);  // the case is real
  o.non_negative = NonNegative::Constant;
  FitStats stats;
  const RowMatrixXd limited = fit_vertex_values(m, s, face_moments(m, s, values), prior, o, &stats);
  EXPECT_GE(limited.col(0).minCoeff(), 0.0);
  EXPECT_EQ(stats.limited_vertices, static_cast<size_t>(negative));
  for (Eigen::Index i = 0; i < plain.rows(); ++i) EXPECT_EQ(limited(i, 0), std::max(plain(i, 0), 0.0));
}

TEST(FitNonNegative, DirectionsKeepTheTransferFunctionAboveThePriorsMinimum) {
  // Order 2 (4 coefficients): an unshadowed cosine lobe, 0 on the lower hemisphere, rotated by a
  // step across the grid; the fit's mix of the two lobes overshoots into negative values. At the
  // 128 Fibonacci directions of keep_non_negative, the limited transfer function stays at or above
  // min(0, the prior's minimum there), vertex by vertex.
  const Mesh m = test::build(test::grid(4, 0.25));
  SampleOptions so;
  so.per_triangle = 128;
  const SurfaceSamples s = make_surface_samples(m, so);
  const Eigen::VectorXd up = unshadowed_transfer(2, Eigen::Vector3d::UnitZ()), side = unshadowed_transfer(2, Eigen::Vector3d::UnitX());
  auto lobe = [&](const Eigen::Vector3d& p) { return p.x() > 0.37 ? side : up; };
  RowMatrixXd values(Eigen::Index(s.size()), 4), prior(Eigen::Index(m.num_vertices()), 4);
  for (Eigen::Index i = 0; i < values.rows(); ++i) values.row(i) = lobe(s.points.row(i).transpose()).transpose();
  for (uint32_t i = 0; i < m.num_vertices(); ++i) prior.row(i) = lobe(m.point(i)).transpose();
  FitOptions o = plain_fit();
  o.alpha = 0;
  o.non_negative = NonNegative::Directions;
  FitStats stats;
  const RowMatrixXd x = fit_vertex_values(m, s, values, prior, o, &stats);
  EXPECT_GT(stats.limited_vertices, 0u);
  RowMatrixXd Y(128, 4);
  for (int d = 0; d < 128; ++d) {
    const double z = 1 - (2.0 * d + 1) / 128, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2.399963229728653 * d;
    sh_eval(2, r * std::cos(phi), r * std::sin(phi), z, Y.row(d).data());
  }
  const RowMatrixXd plain_x = fit_vertex_values(m, s, values, prior, plain_fit());
  bool plain_went_below = false;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const double floor = std::min(0.0, (Y * prior.row(i).transpose()).minCoeff());
    EXPECT_GE((Y * x.row(i).transpose()).minCoeff(), floor - 1e-12) << "vertex " << i;
    plain_went_below |= (Y * plain_x.row(i).transpose()).minCoeff() < floor - 1e-6;
  }
  EXPECT_TRUE(plain_went_below);  // without the limit the bound is broken: the test has power
  EXPECT_GE(x.col(0).minCoeff(), 0.0);
}

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

TEST(Fit, TheUnshadowedCorrectionFollowsEachVertexsOpenShareWhereNoSampleReachesIt) {
  // No face sampled: every vertex keeps its prior, corrected by the known part's projection,
  // P(w·t_u) − w·t_u(n), w its open share (DC against an open point's). For a prior of s·t_u at
  // every vertex, w = s and the projection is linear: the values are s·P(t_u), exactly.
  const Mesh m = test::build(test::icosphere(2));
  SampleOptions so;
  so.per_triangle = 4;
  const SurfaceSamples s = make_surface_samples(m, so, std::vector<double>(m.num_faces(), 0.0));
  const FaceMoments moments{RowMatrixXd::Zero(3 * Eigen::Index(m.num_faces()), 16), {}};
  FitOptions o;
  o.unshadowed_order = 4;
  const RowMatrixXd t_u = unshadowed_at(m.normals, 4), projected = unshadowed_projection(m, 4);
  for (double share : {1.0, 0.5, 0.0}) {
    FitStats st;
    const RowMatrixXd x = fit_vertex_values(m, s, moments, share * t_u, o, &st);
    EXPECT_LT((x - share * projected).cwiseAbs().maxCoeff(), 1e-12 * projected.cwiseAbs().maxCoeff()) << "share " << share;
    EXPECT_EQ(st.unshadowed_iterations > 0, share > 0);  // nothing open, nothing to project
    EXPECT_EQ(st.unsupported, m.num_vertices());  // no row for any vertex: nothing assembled
  }
  // RGB transfer (three blocks of 16): each channel corrected alike.
  const RowMatrixXd rgb = fit_vertex_values(m, s, FaceMoments{RowMatrixXd::Zero(3 * Eigen::Index(m.num_faces()), 48), {}},
                                            t_u.replicate(1, 3), o);
  EXPECT_LT((rgb - projected.replicate(1, 3)).cwiseAbs().maxCoeff(), 1e-12 * projected.cwiseAbs().maxCoeff());
  // Not transfer of that order: refused, naming what is wrong.
  EXPECT_THROW(fit_vertex_values(m, s, FaceMoments{RowMatrixXd::Zero(3 * Eigen::Index(m.num_faces()), 9), {}}, t_u.leftCols(9), o),
               InputError);
}

}  // namespace
}  // namespace prtsub
