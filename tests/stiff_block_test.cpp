#include "prtsub/prt/stiff_block.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <vector>

#include "prtsub/prt/sampling.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

// Symmetric, diagonally dominant (so positive definite) by `margin`: a chain with long links.
RowSparseMatrixd linked_chain(Eigen::Index n, double margin) {
  std::vector<Eigen::Triplet<double>> t;
  std::vector<double> sum(size_t(n), 0.0);
  Rng rng(5, 0);
  auto link = [&](Eigen::Index i, Eigen::Index j) {
    const double v = -0.1 - rng.uniform();
    t.emplace_back(i, j, v), t.emplace_back(j, i, v);
    sum[size_t(i)] -= v, sum[size_t(j)] -= v;
  };
  for (Eigen::Index i = 0; i + 1 < n; ++i) link(i, i + 1);
  for (Eigen::Index i = 0; i + 31 < n; i += 7) link(i, i + 31);
  for (Eigen::Index i = 0; i < n; ++i) t.emplace_back(i, i, sum[size_t(i)] + margin);
  RowSparseMatrixd A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

TEST(StiffBlock, ItsInverseIsTheDenseInverseOfThePrincipalBlock) {
  const Eigen::Index n = 400;
  const RowSparseMatrixd A = linked_chain(n, 1e-3);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < n; i += 3) rows.push_back(i);
  for (Eigen::Index i = 200; i < 260; ++i)
    if (i % 3) rows.push_back(i);
  std::sort(rows.begin(), rows.end());
  StiffBlock block(A, rows);
  const Eigen::Index m = Eigen::Index(rows.size());
  EXPECT_EQ(block.rows(), rows);
  EXPECT_GE(block.predicted_factor_entries(), size_t(m));  // at least the diagonal
  ASSERT_TRUE(block.factorise());
  const RowBlockInverse inverse = block.inverse();
  EXPECT_EQ(inverse.rows, rows);
  // Independently: A_SS densely, by its entries.
  Eigen::MatrixXd dense(m, m);
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index b = 0; b < m; ++b) dense(a, b) = A.coeff(rows[size_t(a)], rows[size_t(b)]);
  Eigen::MatrixXd r = Eigen::MatrixXd::Random(m, 4), z = r;
  inverse.solve(z);
  EXPECT_LT((dense * z - r).cwiseAbs().maxCoeff(), 1e-9 * r.cwiseAbs().maxCoeff());
  EXPECT_LT((z - dense.llt().solve(r)).cwiseAbs().maxCoeff(), 1e-8 * z.cwiseAbs().maxCoeff());
}

TEST(StiffBlock, RefusesBadRowsAndSaysWhenTheBlockIsNotPositiveDefinite) {
  const Eigen::Index n = 50;
  RowSparseMatrixd A = linked_chain(n, 1e-3);
  EXPECT_THROW(StiffBlock(A, {3, 2}), InputError);
  EXPECT_THROW(StiffBlock(A, {3, 3}), InputError);
  EXPECT_THROW(StiffBlock(A, {-1}), InputError);
  EXPECT_THROW(StiffBlock(A, {n}), InputError);
  // No rows: nothing to factorise, and M is the identity.
  StiffBlock none(A, {});
  EXPECT_TRUE(none.factorise());
  EXPECT_TRUE(none.inverse().rows.empty());
  // A row of the block with a negative diagonal: not positive definite.
  A.coeffRef(10, 10) = -1.0;
  StiffBlock indefinite(A, {9, 10, 11});
  EXPECT_THROW(indefinite.inverse(), SolverError);  // not factorised yet
  EXPECT_FALSE(indefinite.factorise());
  EXPECT_THROW(indefinite.inverse(), SolverError);
}

}  // namespace
}  // namespace prtsub
