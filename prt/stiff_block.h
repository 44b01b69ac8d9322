// The rows of a symmetric positive definite system that conjugate gradients cannot reach by
// Jacobi scaling alone, factorised on their own: CG's preconditioner on the fit's stiff systems.
#pragma once

#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "prtsub/prt/block_cg.h"

namespace prtsub {

//! A's principal block on some rows, A_SS, factorised by CHOLMOD (supernodal Cholesky, AMD
//! ordering). Its inverse on those rows and the identity elsewhere is CG's preconditioner
//! (RowBlockInverse) for A scaled to a unit diagonal.
class StiffBlock {
 public:
  //! Takes A_SS out of A and analyses its pattern; factorise() before inverse().
  //! \param A n by n, symmetric, both triangles stored
  //! \param rows S: ascending, no repeats
  //! \throw InputError if rows are not ascending indices of A
  StiffBlock(const RowSparseMatrixd& A, std::vector<Eigen::Index> rows);
  ~StiffBlock();
  StiffBlock(const StiffBlock&) = delete;
  StiffBlock& operator=(const StiffBlock&) = delete;

  //! The factor's entries that the symbolic analysis predicts: what factorise() will cost.
  size_t predicted_factor_entries() const { return predicted_entries_; }
  size_t block_nonzeros() const { return size_t(block_.nonZeros()); }
  const std::vector<Eigen::Index>& rows() const { return rows_; }

  //! false if A_SS is not numerically positive definite (a pivot at or below zero)
  bool factorise();
  //! M on the rows: A_SS⁻¹ (after a successful factorise()); the object must outlive it
  RowBlockInverse inverse() const;

 private:
  struct Factor;
  std::vector<Eigen::Index> rows_;
  Eigen::SparseMatrix<double> block_;  // lower triangle of A_SS
  std::unique_ptr<Factor> factor_;
  size_t predicted_entries_ = 0;
  bool factored_ = false;
};

}  // namespace prtsub
