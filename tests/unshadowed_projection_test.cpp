// The exact projection of the unshadowed transfer: checked against an independent quadrature
// (Galerkin orthogonality and the L2 error it minimises), closed forms on flat meshes, the hard
// cases (zero-area faces, isolated vertices, huge offsets, tiny scales, order 10) and threads.
#include "prtsub/prt/unshadowed_projection.h"

#include <gtest/gtest.h>

#include <cmath>

#include "helpers.h"
#include "prtsub/prt/sh.h"

namespace prtsub {
namespace {

// t_u at the normalised interpolated normal of face f at barycentrics (b0, b1, b2).
Eigen::VectorXd truth(const Mesh& m, size_t f, double b0, double b1, double b2, int order) {
  const Triangle& t = m.triangles[f];
  Eigen::Vector3d n =
      b0 * m.normals.row(t[0]) + b1 * m.normals.row(t[1]) + b2 * m.normals.row(t[2]);
  return unshadowed_transfer(order, n.normalized());
}

// An independent quadrature: Gauss–Legendre on the square mapped to each face (the collapsed
// Duffy map), `g` points per direction.
template <class Body>
void integrate(const Mesh& m, int g, Body&& body) {
  std::vector<double> x, w;
  test::gauss_legendre(g, x, w);
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const Triangle& t = m.triangles[f];
    const double area = triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2]));
    if (!(area > 0)) continue;
    for (int i = 0; i < g; ++i)
      for (int j = 0; j < g; ++j) {
        const double s = 0.5 * (x[size_t(i)] + 1), r = 0.5 * (x[size_t(j)] + 1);
        const double b1 = s * (1 - r), b2 = s * r, b0 = 1 - b1 - b2;
        const double weight =
            0.25 * w[size_t(i)] * w[size_t(j)] * s * 2 * area;  // Jacobian of the map
        body(f, b0, b1, b2, weight);
      }
  }
}

TEST(UnshadowedProjection, IsTheL2ProjectionAnIndependentQuadratureFinds) {
  // A coarse sphere: its normals turn ~20° across a face, so t_u is far from linear there.
  const Mesh m = test::build(test::icosphere(2));
  const int order = 4, K = 16;
  UnshadowedProjectionStats st;
  const RowMatrixXd x = unshadowed_projection(m, order, {}, &st);
  const RowMatrixXd at_vertices = unshadowed_at(m.normals, order);
  // Galerkin orthogonality: ∫ h_i (t_u − Σ h_j x_j) = 0 for every vertex i, by the independent
  // rule.
  RowMatrixXd residual = RowMatrixXd::Zero(x.rows(), K);
  double err_projection = 0, err_interpolation = 0, scale = 0;
  integrate(m, 12, [&](size_t f, double b0, double b1, double b2, double w) {
    const Triangle& t = m.triangles[f];
    const Eigen::VectorXd tu = truth(m, f, b0, b1, b2, order);
    const Eigen::VectorXd g =
        b0 * x.row(t[0]).transpose() + b1 * x.row(t[1]).transpose() + b2 * x.row(t[2]).transpose();
    const Eigen::VectorXd li = b0 * at_vertices.row(t[0]).transpose() +
                               b1 * at_vertices.row(t[1]).transpose() +
                               b2 * at_vertices.row(t[2]).transpose();
    const double b[3] = {b0, b1, b2};
    for (int c = 0; c < 3; ++c) residual.row(t[c]) += w * b[c] * (tu - g).transpose();
    err_projection += w * (tu - g).squaredNorm(), err_interpolation += w * (tu - li).squaredNorm(),
        scale += w * tu.squaredNorm();
  });
  const double area = test::total_area(m);
  const double typical =
      std::sqrt(scale / area) * area / double(x.rows());  // ∫h_i ‖t_u‖ for a typical vertex
  std::printf("Galerkin residual %.2e of a typical right-hand side\n",
              residual.cwiseAbs().maxCoeff() / typical);
  EXPECT_LT(residual.cwiseAbs().maxCoeff(), 1e-6 * typical);
  // What it buys: the L2 error is the least any vertex values reach, well under interpolation's.
  const double ratio = std::sqrt(err_projection / err_interpolation);
  std::printf(
      "icosphere(2): interpolation %.4f%%, projection %.4f%% of ||t_u|| (ratio %.3f), %d CG "
      "passes, %zu points\n",
      100 * std::sqrt(err_interpolation / scale), 100 * std::sqrt(err_projection / scale), ratio,
      st.iterations, st.quadrature_points);
  EXPECT_LT(ratio, 0.7);
  EXPECT_GT(ratio,
            0.2);  // a linear interpolant cannot follow t_u's curvature; nothing makes it vanish
  // Zonal bands of odd l > 1 are zero for the clamped cosine: order 4's band 3 stays zero.
  EXPECT_EQ(x.rightCols(7).cwiseAbs().maxCoeff(), 0.0);
}

TEST(UnshadowedProjection, IsExactWhereTheNormalIsConstant) {
  // One normal everywhere: t_u is constant, and the mass matrix reproduces constants.
  const Mesh m = test::build(test::grid(6, 0.6));
  const RowMatrixXd x = unshadowed_projection(m, 5);
  const Eigen::VectorXd expected = unshadowed_transfer(5, Eigen::Vector3d::UnitZ());
  // (to the float precision the faces' integrals are kept in)
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    EXPECT_LT((x.row(i).transpose() - expected).norm(), 1e-6 * expected.norm());
}

TEST(UnshadowedProjection, VerticesWithoutAreaKeepTheirOwnValueAndNothingIsNaN) {
  // A sphere plus a zero-area face (three collinear points, kept by the loader and counted).
  RawMesh raw = test::icosphere(1);
  const auto base = raw.positions.rows();
  raw.positions.conservativeResize(base + 3, Eigen::NoChange);
  raw.positions.bottomRows(3) << 3, 0, 0, 4, 0, 0, 5, 0, 0;
  for (int k = 0; k < 3; ++k) raw.face_indices.push_back(base + k);
  raw.face_offsets.push_back(raw.face_indices.size());
  const Mesh m = test::build(raw);
  ASSERT_EQ(m.num_faces(), 81u);
  UnshadowedProjectionStats st;
  const RowMatrixXd x = unshadowed_projection(m, 4, {}, &st);
  EXPECT_TRUE(x.allFinite());
  EXPECT_GE(st.fixed_vertices, 3u);
  const RowMatrixXd own = unshadowed_at(m.normals, 4);
  for (uint32_t v : m.triangles.back()) EXPECT_EQ((x.row(v) - own.row(v)).norm(), 0.0);
}

TEST(UnshadowedProjection, DependsOnlyOnTheShapeAndNotOnThreadsOffsetsOrScale) {
  const RawMesh raw = test::icosphere(2);
  const Mesh m = test::build(raw);
  UnshadowedProjectionOptions one, two;
  one.threads = 1, two.threads = 2;
  const RowMatrixXd a = unshadowed_projection(m, 6, one), b = unshadowed_projection(m, 6, two);
  EXPECT_EQ((a - b).cwiseAbs().maxCoeff(), 0.0);  // bit for bit
  for (const auto& [scale, offset] : {std::pair<double, double>{1e-4, 0.0}, {1.0, 1e6}}) {
    const RowMatrixXd c = unshadowed_projection(
        test::build(test::transformed(raw, scale, Eigen::Vector3d::Constant(offset))), 6);
    EXPECT_LT((a - c).cwiseAbs().maxCoeff(), 1e-7 * a.cwiseAbs().maxCoeff())
        << "scale " << scale << ", offset " << offset;
  }
}

TEST(UnshadowedProjection, HighOrdersStayFiniteAndKeepTheirZeroBands) {
  const Mesh m = test::build(test::icosphere(1));
  const RowMatrixXd x = unshadowed_projection(m, 10);
  ASSERT_TRUE(x.allFinite());
  for (int l = 3; l < 10; l += 2)  // odd bands above 1: Â_l = 0
    for (int mm = -l; mm <= l; ++mm)
      EXPECT_EQ(x.col(sh_index(l, mm)).cwiseAbs().maxCoeff(), 0.0) << "band " << l;
  EXPECT_GT(x.col(sh_index(8, 0)).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace prtsub
