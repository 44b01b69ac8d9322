#include "prtsub/prt/block_cg.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cstdio>
#include <vector>

#include "prtsub/prt/huge_pages.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

// A random symmetric positive definite matrix shaped like a mesh's: a 1-D chain with a few long
// links, unit diagonal after scaling, diagonally dominant by a margin so its condition is modest.
RowSparseMatrixd chain(Eigen::Index n, uint64_t seed) {
  std::vector<Eigen::Triplet<double>> t;
  Rng rng(seed, 0);
  std::vector<double> row_sum(size_t(n), 0.0);
  auto link = [&](Eigen::Index i, Eigen::Index j) {
    const double v = -rng.uniform();
    t.emplace_back(i, j, v), t.emplace_back(j, i, v);
    row_sum[size_t(i)] += -v, row_sum[size_t(j)] += -v;
  };
  for (Eigen::Index i = 0; i + 1 < n; ++i) link(i, i + 1);
  for (Eigen::Index i = 0; i + 97 < n; i += 13) link(i, i + 97);
  for (Eigen::Index i = 0; i < n; ++i) t.emplace_back(i, i, 0.05 + row_sum[size_t(i)]);
  RowSparseMatrixd A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

RowMatrixXd random_columns(Eigen::Index n, Eigen::Index K, uint64_t seed) {
  RowMatrixXd B(n, K);
  Rng rng(seed, 1);
  for (Eigen::Index i = 0; i < B.size(); ++i) B.data()[i] = rng.uniform() - 0.5;
  return B;
}

TEST(BlockCg, EveryColumnMatchesADenseSolveToItsTolerance) {
  const Eigen::Index n = 1500, K = 5;  // a block of rows and a partial one
  const RowSparseMatrixd A = chain(n, 7);
  RowMatrixXd B = random_columns(n, K, 8);
  B.col(3).setZero();  // a zero right-hand side has the zero solution, whatever the start
  const Eigen::MatrixXd dense = Eigen::MatrixXd(A).ldlt().solve(Eigen::MatrixXd(B));
  RowMatrixXd X = random_columns(n, K, 9);  // a warm start far from the solution
  BlockCgOptions o;
  o.tolerance = 1e-10, o.max_iterations = 5000;
  const BlockCgResult r = block_conjugate_gradient(A, B, X, o);
  ASSERT_TRUE(r.converged);
  EXPECT_GT(r.iterations, 10);
  EXPECT_LE(r.relative_residual, 1e-10);
  // The true residual, computed independently of CG's recurrence.
  for (Eigen::Index q = 0; q < K; ++q) {
    const Eigen::VectorXd res = Eigen::VectorXd(B.col(q)) - A * Eigen::VectorXd(X.col(q));
    if (q == 3) EXPECT_EQ(X.col(q).cwiseAbs().maxCoeff(), 0.0);
    else EXPECT_LT(res.norm(), 1e-9 * B.col(q).norm()) << "column " << q;
  }
  EXPECT_LT((Eigen::MatrixXd(X) - dense).cwiseAbs().maxCoeff(), 1e-7 * dense.cwiseAbs().maxCoeff());
}

TEST(BlockCg, TheResultDoesNotDependOnTheThreadCount) {
  const Eigen::Index n = 5000, K = 3;
  const RowSparseMatrixd A = chain(n, 11);
  const RowMatrixXd B = random_columns(n, K, 12);
  RowMatrixXd one = RowMatrixXd::Zero(n, K), two = one;
  block_conjugate_gradient(A, B, one, {1e-12, 5000, 1});
  block_conjugate_gradient(A, B, two, {1e-12, 5000, 2});
  EXPECT_EQ(one, two);  // bit for bit
}

TEST(BlockCg, StartingAtTheSolutionTakesNoIterations) {
  const RowSparseMatrixd A = chain(100, 3);
  const RowMatrixXd X0 = random_columns(100, 2, 4);
  RowMatrixXd X = X0;
  const BlockCgResult r = block_conjugate_gradient(A, A * X0, X, {1e-8, 100, 0});
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(X, X0);
}

TEST(BlockCg, IndefiniteOrStalledSystemsSayTheyDidNotConverge) {
  // diag(1, …, 1, −1): pᵀAp ≤ 0 can occur; the result must say so and stay finite.
  const Eigen::Index n = 50;
  RowSparseMatrixd A(n, n);
  for (Eigen::Index i = 0; i < n; ++i) A.insert(i, i) = i + 1 == n ? -1.0 : 1.0 + 0.1 * double(i);
  RowMatrixXd B = RowMatrixXd::Zero(n, 1);
  B(n - 1, 0) = 1;  // only the negative direction: the first step finds pᵀAp < 0
  RowMatrixXd X = RowMatrixXd::Zero(n, 1);
  BlockCgResult r = block_conjugate_gradient(A, B, X, {1e-10, 100, 0});
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(X.allFinite());
  // An iteration cap below what the system needs.
  const RowSparseMatrixd C = chain(2000, 5);
  RowMatrixXd Y = RowMatrixXd::Zero(2000, 2);
  r = block_conjugate_gradient(C, random_columns(2000, 2, 6), Y, {1e-10, 3, 0});
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 3);
  EXPECT_GT(r.relative_residual, 1e-10);
  EXPECT_TRUE(Y.allFinite());
}

// A matrix still being filled (uncompressed) has reserved slots between its rows whose contents
// are whatever the allocator left. The solve must read only the written entries: fill the gaps
// with junk and get exactly the compressed matrix's answer.
TEST(BlockCg, DoesNotDependOnTheCallersStorageState) {
  const RowSparseMatrixd C = chain(300, 9);
  RowSparseMatrixd U(C.rows(), C.cols());
  U.reserve(Eigen::VectorXi::Constant(C.rows(), 8));  // room for 8 per row, far more than used
  for (Eigen::Index i = 0; i < C.rows(); ++i)
    for (RowSparseMatrixd::InnerIterator it(C, i); it; ++it) U.insert(i, it.col()) = it.value();
  ASSERT_FALSE(U.isCompressed());
  for (Eigen::Index i = 0; i < U.rows(); ++i)
    for (auto k = U.outerIndexPtr()[i] + U.innerNonZeroPtr()[i]; k < U.outerIndexPtr()[i + 1]; ++k)
      U.valuePtr()[k] = 1e6, U.innerIndexPtr()[k] = 0;  // junk in the gaps
  const RowMatrixXd B = random_columns(300, 3, 10);
  RowMatrixXd x_compressed = RowMatrixXd::Zero(300, 3), x_filling = RowMatrixXd::Zero(300, 3);
  const BlockCgResult a = block_conjugate_gradient(C, B, x_compressed);
  const BlockCgResult b = block_conjugate_gradient(U, B, x_filling);
  EXPECT_TRUE(a.converged);
  EXPECT_TRUE(b.converged);
  EXPECT_EQ(x_compressed, x_filling);
}

// A unit-diagonal system shaped like the fit's stiff ones: most rows held by their diagonal
// (couplings of 0.2), and a run of `stiff` rows that form a nearly singular 1-D Laplacian (a
// regulariser with hardly any mass), weakly tied to the rest.
RowSparseMatrixd stiff_chain(Eigen::Index n, Eigen::Index first, Eigen::Index stiff) {
  std::vector<Eigen::Triplet<double>> t;
  auto in = [&](Eigen::Index i) { return i >= first && i < first + stiff; };
  std::vector<double> diag(size_t(n), 0.0);
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    const double v = in(i) && in(i + 1) ? -1.0 : in(i) || in(i + 1) ? -0.05 : -0.2;
    t.emplace_back(i, i + 1, v), t.emplace_back(i + 1, i, v);
    diag[size_t(i)] -= v, diag[size_t(i + 1)] -= v;
  }
  for (Eigen::Index i = 0; i < n; ++i) t.emplace_back(i, i, in(i) ? diag[size_t(i)] + 1e-4 : 1.0);
  RowSparseMatrixd A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  const Eigen::VectorXd d = A.diagonal().cwiseSqrt().cwiseInverse();
  return RowSparseMatrixd(d.asDiagonal() * A * d.asDiagonal());
}

TEST(BlockCg, InvertingTheStiffRowsBlockConvergesWhereJacobiCrawls) {
  const Eigen::Index n = 2000, first = 700, stiff = 600, K = 3;
  const RowSparseMatrixd A = stiff_chain(n, first, stiff);
  const RowMatrixXd B = random_columns(n, K, 21);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = first; i < first + stiff; ++i) rows.push_back(i);
  // A_SS⁻¹ from a dense factorisation: independent of the code under test.
  Eigen::MatrixXd block(stiff, stiff);
  for (Eigen::Index a = 0; a < stiff; ++a)
    for (Eigen::Index b = 0; b < stiff; ++b) block(a, b) = A.coeff(first + a, first + b);
  const Eigen::LLT<Eigen::MatrixXd> llt(block);
  ASSERT_EQ(llt.info(), Eigen::Success);
  RowBlockInverse inverse{rows, [&](Eigen::MatrixXd& r) { r = llt.solve(r); }};
  BlockCgOptions o;
  o.tolerance = 1e-10, o.max_iterations = 5000, o.predict_stall = false;
  RowMatrixXd jacobi = RowMatrixXd::Zero(n, K), blocked = jacobi, general = jacobi;
  const BlockCgResult rj = block_conjugate_gradient(A, B, jacobi, o);
  const BlockCgResult rb = block_conjugate_gradient(A, B, blocked, o, inverse);
  // The same M as a general preconditioner (Z = R off the block): the same iterates up to rounding.
  const BlockCgResult rg = block_conjugate_gradient(A, B, general, o, [&](const RowMatrixXd& r, RowMatrixXd& z) {
    z = r;
    Eigen::MatrixXd rs = r.middleRows(first, stiff);
    inverse.solve(rs);
    z.middleRows(first, stiff) = rs;
  });
  ASSERT_TRUE(rj.converged && rb.converged && rg.converged);
  // Measured: Jacobi 612 iterations, the block 16. The stiff run's condition (~4/1e-4) sets
  // Jacobi's count; with it inverted, what is left is diagonally dominant.
  std::printf("Jacobi %d iterations, stiff block inverted %d\n", rj.iterations, rb.iterations);
  EXPECT_GT(rj.iterations, 300);
  EXPECT_LT(rb.iterations, 30);
  EXPECT_EQ(rb.iterations, rg.iterations);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(A).llt().solve(Eigen::MatrixXd(B));
  EXPECT_LT((Eigen::MatrixXd(blocked) - dense).cwiseAbs().maxCoeff(), 1e-7 * dense.cwiseAbs().maxCoeff());
  EXPECT_LT((blocked - general).cwiseAbs().maxCoeff(), 1e-9 * dense.cwiseAbs().maxCoeff());
  // Bit for bit whatever the thread count.
  RowMatrixXd one = RowMatrixXd::Zero(n, K), two = one;
  block_conjugate_gradient(A, B, one, {1e-10, 5000, 1}, inverse);
  block_conjugate_gradient(A, B, two, {1e-10, 5000, 2}, inverse);
  EXPECT_EQ(one, two);
  // Rows out of order or out of range are refused; no rows is Jacobi.
  RowBlockInverse bad = inverse;
  std::swap(bad.rows[0], bad.rows[1]);
  EXPECT_THROW(block_conjugate_gradient(A, B, one, o, bad), InputError);
  bad.rows = {n};
  EXPECT_THROW(block_conjugate_gradient(A, B, one, o, bad), InputError);
  RowMatrixXd none = RowMatrixXd::Zero(n, K);
  EXPECT_EQ(block_conjugate_gradient(A, B, none, o, RowBlockInverse{}).iterations, rj.iterations);
  EXPECT_EQ(none, jacobi);
}

}  // namespace
}  // namespace prtsub

// Huge-page advice (prt/huge_pages.h) is a hint to the kernel: it must leave every value as
// written, on ranges of any alignment and size, and a HugeVector must behave as a std::vector.
TEST(HugePages, AdviceLeavesValuesAsWrittenAndHugeVectorsBehaveAsVectors) {
  const size_t n = (size_t(5) << 20) + 3;  // 40 MiB of doubles, plus an unaligned tail
  std::vector<double> plain(n);
  prtsub::prefer_huge_pages(plain.data() + 1, (n - 1) * sizeof(double));  // unaligned start
  prtsub::prefer_huge_pages(nullptr, 1 << 30);
  prtsub::prefer_huge_pages(plain.data(), 100);
  for (size_t i = 0; i < n; ++i) plain[i] = double(i) * 0.5;
  prtsub::HugeVector<double> huge(n, 0.0);
  for (size_t i = 0; i < n; ++i) huge[i] = double(i) * 0.5;
  EXPECT_TRUE(std::equal(plain.begin(), plain.end(), huge.begin()));
  prtsub::HugeVector<double> moved = std::move(huge);
  moved.push_back(-1.0);
  ASSERT_EQ(moved.size(), n + 1);
  EXPECT_EQ(moved[n - 1], double(n - 1) * 0.5);
  EXPECT_EQ(moved[n], -1.0);
}
