#include "prtsub/prt/multigrid.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <vector>

#include "prtsub/prt/block_cg.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

// The fit's hard case in miniature: on an m by m grid of spacing h = 1/m, a mass term h²·I
// beside a 5-point Laplacian that does not shrink with h (the regulariser's entries are
// scale-free), scaled to a unit diagonal. Its smallest eigenvalue falls as h², so Jacobi-CG's
// iterations grow as 1/h; the Laplacian barely penalises smooth functions, which is what the
// coarse levels are for. Row order is row by row, as the fit's breadth-first order is compact.
RowSparseMatrixd stiff_grid(int m) {
  const double h = 1.0 / m;
  std::vector<Eigen::Triplet<double>> t;
  auto at = [m](int i, int j) { return Eigen::Index(i) * m + j; };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      double degree = 0;
      const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
      for (int k = 0; k < 4; ++k) {
        const int a = i + di[k], b = j + dj[k];
        if (a < 0 || b < 0 || a >= m || b >= m) continue;
        t.emplace_back(at(i, j), at(a, b), -1.0);
        degree += 1;
      }
      t.emplace_back(at(i, j), at(i, j), degree + h * h);
    }
  RowSparseMatrixd A(Eigen::Index(m) * m, Eigen::Index(m) * m);
  A.setFromTriplets(t.begin(), t.end());
  const Eigen::VectorXd s = A.diagonal().cwiseSqrt().cwiseInverse();
  return s.asDiagonal() * A * s.asDiagonal();
}

RowMatrixXd random_columns(Eigen::Index n, Eigen::Index K, uint64_t seed) {
  RowMatrixXd B(n, K);
  Rng rng(seed, 1);
  for (Eigen::Index i = 0; i < B.size(); ++i) B.data()[i] = rng.uniform() - 0.5;
  return B;
}

// Iterations to a relative residual of 1e-8 from zero, with or without the multigrid cycle.
int iterations(const RowSparseMatrixd& A, const RowMatrixXd& B, bool multigrid, MultigridOptions mo = {}) {
  RowMatrixXd X = RowMatrixXd::Zero(A.rows(), B.cols());
  BlockCgOptions o;
  o.tolerance = 1e-8, o.max_iterations = 5000, o.predict_stall = false;
  BlockPreconditioner p;
  std::unique_ptr<Multigrid> mg;
  if (multigrid) {
    mg = std::make_unique<Multigrid>(A, mo);
    p = [&](const RowMatrixXd& r, RowMatrixXd& z) { mg->apply(r, z); };
  }
  const BlockCgResult r = block_conjugate_gradient(A, B, X, o, p);
  EXPECT_TRUE(r.converged);
  // The true residual, not CG's recurrence.
  const RowMatrixXd residual = B - A * X;
  EXPECT_LT(residual.norm(), 1e-7 * B.norm());
  return r.iterations;
}

TEST(Multigrid, IterationsStayFlatWhereJacobiGrowsWithTheGrid) {
  // 32², 64², 128²: Jacobi-CG doubles per halving of h (measured 146, 295, 590), the
  // preconditioned count barely moves (14, 15, 16).
  // Coarsest 200 so that even the smallest grid has three levels.
  MultigridOptions mo;
  mo.coarsest = 200;
  std::vector<int> jacobi, cycled;
  for (int m : {32, 64, 128}) {
    const RowSparseMatrixd A = stiff_grid(m);
    const RowMatrixXd B = random_columns(A.rows(), 3, 5);
    jacobi.push_back(iterations(A, B, false));
    cycled.push_back(iterations(A, B, true, mo));
  }
  std::printf("iterations, Jacobi-CG: %d %d %d; multigrid: %d %d %d\n", jacobi[0], jacobi[1], jacobi[2], cycled[0], cycled[1], cycled[2]);
  EXPECT_GT(jacobi[1], 1.8 * jacobi[0]);
  EXPECT_GT(jacobi[2], 1.8 * jacobi[1]);
  EXPECT_LE(cycled[2], cycled[0] + 3);
  EXPECT_LT(cycled[0], 20);
  EXPECT_LT(20 * cycled[2], jacobi[2]);
}

TEST(Multigrid, TheCycleIsASymmetricPositiveDefiniteOperator) {
  // CG needs it: uᵀM(v) = vᵀM(u) and vᵀM(v) > 0, to round-off.
  const RowSparseMatrixd A = stiff_grid(48);
  MultigridOptions mo;
  mo.coarsest = 100;
  const Multigrid mg(A, mo);
  ASSERT_GE(mg.stats().unknowns.size(), 3u);
  const RowMatrixXd U = random_columns(A.rows(), 4, 1), V = random_columns(A.rows(), 4, 2);
  RowMatrixXd MU, MV;
  mg.apply(U, MU), mg.apply(V, MV);
  for (Eigen::Index q = 0; q < 4; ++q) {
    const double uv = U.col(q).dot(MV.col(q)), vu = V.col(q).dot(MU.col(q));
    EXPECT_NEAR(uv, vu, 1e-11 * (std::abs(uv) + U.col(q).norm() * MV.col(q).norm()));
    EXPECT_GT(V.col(q).dot(MV.col(q)), 0);
    EXPECT_GT(U.col(q).dot(MU.col(q)), 0);
  }
  // Linear: M(U + 2V) = M(U) + 2M(V).
  RowMatrixXd MW;
  mg.apply(U + 2 * V, MW);
  EXPECT_LT((MW - MU - 2 * MV).cwiseAbs().maxCoeff(), 1e-10 * MW.cwiseAbs().maxCoeff());
  // Operator complexity: each coarse level is a fraction of the one above.
  EXPECT_GT(mg.stats().operator_complexity, 1.0);
  EXPECT_LT(mg.stats().operator_complexity, 2.5);
  for (size_t l = 1; l < mg.stats().unknowns.size(); ++l) EXPECT_LT(mg.stats().unknowns[l], mg.stats().unknowns[l - 1]);
}

TEST(Multigrid, TheResultDoesNotDependOnTheThreadCount) {
  const RowSparseMatrixd A = stiff_grid(80);
  const RowMatrixXd R = random_columns(A.rows(), 3, 9);
  MultigridOptions one, two;
  one.threads = 1, two.threads = 2;
  one.coarsest = two.coarsest = 100;
  const Multigrid a(A, one), b(A, two);
  EXPECT_EQ(a.stats().unknowns, b.stats().unknowns);
  EXPECT_EQ(a.stats().nonzeros, b.stats().nonzeros);
  RowMatrixXd za, zb;
  a.apply(R, za), b.apply(R, zb);
  EXPECT_EQ(za, zb);  // bit for bit
}

TEST(Multigrid, ASmallSystemIsSolvedExactlyAndBadInputThrows) {
  // At most `coarsest` unknowns: one level, the cycle is the Cholesky solve, CG needs one step.
  const RowSparseMatrixd A = stiff_grid(10);
  const Multigrid mg(A);
  EXPECT_EQ(mg.stats().unknowns.size(), 1u);
  const RowMatrixXd B = random_columns(A.rows(), 2, 3);
  RowMatrixXd Z;
  mg.apply(B, Z);
  EXPECT_LT((A * Z - B).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(iterations(A, B, true), 1);
  // Near-null vectors of the wrong length; a matrix with a non-positive diagonal entry.
  EXPECT_THROW((void)Multigrid(A, {}, Eigen::MatrixXd::Ones(A.rows() + 1, 1)), InputError);
  RowSparseMatrixd bad = A;
  bad.coeffRef(5, 5) = 0;
  EXPECT_THROW((void)Multigrid(bad, {}), SolverError);
  // Near-null vectors that some aggregates cannot tell apart (a column that is a multiple of the
  // constant, and a constant coordinate): the QR keeps the directions that exist, and the cycle
  // still converges.
  const RowSparseMatrixd big = stiff_grid(64);
  Eigen::MatrixXd B3(big.rows(), 3);
  B3.col(0).setOnes();
  B3.col(1).setConstant(2.0);
  for (Eigen::Index i = 0; i < big.rows(); ++i) B3(i, 2) = double(i % 64) / 64;
  MultigridOptions mo;
  mo.coarsest = 200;
  const Multigrid rank_deficient(big, mo, B3);
  EXPECT_GE(rank_deficient.stats().unknowns.size(), 2u);
  RowMatrixXd X = RowMatrixXd::Zero(big.rows(), 1);
  const RowMatrixXd b = random_columns(big.rows(), 1, 4);
  BlockCgOptions o;
  o.tolerance = 1e-8, o.max_iterations = 200;
  const BlockCgResult r = block_conjugate_gradient(big, b, X, o, [&](const RowMatrixXd& in, RowMatrixXd& out) { rank_deficient.apply(in, out); });
  EXPECT_TRUE(r.converged);
  EXPECT_TRUE(X.allFinite());
}

}  // namespace
}  // namespace prtsub
