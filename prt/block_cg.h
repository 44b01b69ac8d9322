// Conjugate gradients for a symmetric positive definite sparse system with many right-hand
// sides at once: each column runs its own CG, sharing the passes over the matrix.
#pragma once

#include <Eigen/SparseCore>
#include <functional>
#include <vector>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

using RowSparseMatrixd = Eigen::SparseMatrix<double, Eigen::RowMajor>;

struct BlockCgOptions {
  double tolerance = 1e-10;  //!< stop a column when ‖b − Ax‖ ≤ tolerance·‖b‖
  int max_iterations = 300;
  int threads = 0;           //!< 0: every core; the result does not depend on it
  //! From iteration 20, stop as soon as the last 10 iterations' rate of decrease predicts that
  //! max_iterations will not reach the tolerance.
  bool predict_stall = true;
};

//! Rows first..last−1 of A·in into out (or added to it), for row-major blocks of K columns:
//! the pass over the matrix that block CG and the multigrid cycle share.
void multiply_sparse_rows(const RowSparseMatrixd& A, const double* in, double* out, Eigen::Index K, Eigen::Index first,
                          Eigen::Index last, bool accumulate = false);

//! Z ≈ A⁻¹R for n by K residuals R: a symmetric positive definite operator (a multigrid cycle).
using BlockPreconditioner = std::function<void(const RowMatrixXd& R, RowMatrixXd& Z)>;

//! The identity except on a few rows S, where it is the inverse of A's block on them:
//! M = A_SS there, I elsewhere (for A scaled to a unit diagonal). It is what a system needs whose
//! stiff rows are few (fit.cpp); CG then keeps only an |S| by K array for M⁻¹R, not an n by K one.
struct RowBlockInverse {
  std::vector<Eigen::Index> rows;  //!< S, ascending, no repeats
  //! In place: the residual's rows S (|S| by K) become A_SS⁻¹ times them.
  std::function<void(Eigen::MatrixXd& block)> solve;
};

//! \throw InputError (naming `what`) unless `rows` are ascending, unrepeated indices below n
void check_block_rows(const std::vector<Eigen::Index>& rows, Eigen::Index n, const char* what);

struct BlockCgResult {
  int iterations = 0;             //!< of the slowest column
  bool converged = false;         //!< every column reached the tolerance
  double relative_residual = 0;   //!< the worst column's ‖b − Ax‖ / ‖b‖ at the end
  bool predicted_stall = false;   //!< stopped early: the cap would not have been enough
};

//! Solves A X = B column by column, with the preconditioner if one is given (without one, scale A
//! to a unit diagonal first: that is Jacobi preconditioning). X holds the starting guess and receives the solution. Stops early
//! and reports converged = false if a column breaks down (pᵀAp ≤ 0: A is not positive definite),
//! does not converge within max_iterations, or is predicted not to; X then holds the last
//! finite iterate.
//! \param A n by n, both triangles stored
//! \param B n by K, by value: its storage becomes the residual's (move it in if you are done with it)
BlockCgResult block_conjugate_gradient(const RowSparseMatrixd& A, RowMatrixXd B, RowMatrixXd& X,
                                       const BlockCgOptions& options = {}, const BlockPreconditioner& preconditioner = {});
//! The same with M = RowBlockInverse: identity off its rows, their block's inverse on them.
//! \throw InputError if its rows are not ascending indices of A
BlockCgResult block_conjugate_gradient(const RowSparseMatrixd& A, RowMatrixXd B, RowMatrixXd& X, const BlockCgOptions& options,
                                       const RowBlockInverse& block);

}  // namespace prtsub
