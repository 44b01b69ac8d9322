// Smoothed-aggregation algebraic multigrid: a preconditioner for block conjugate gradients on a
// symmetric positive definite sparse system whose iteration count grows with the mesh (the fit's
// system where the regulariser outweighs the mass: refined meshes, slivers beside large faces).
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "prtsub/prt/block_cg.h"

namespace prtsub {

struct MultigridOptions {
  //! Below this many unknowns a level is solved directly (a sparse Cholesky factor).
  Eigen::Index coarsest = 2000;
  int max_levels = 12;
  //! j is a strong neighbour of i when |a_ij| ≥ strength · √(a_ii a_jj); only strong neighbours
  //! join an aggregate. 0 (every neighbour): the fit's scaled rows have many small couplings, and
  //! a threshold such as the textbook's 0.08 leaves too few strong ones for the levels to shrink.
  double strength = 0.0;
  int smoothing_steps = 1;  //!< damped Jacobi steps before and after each coarse correction
  int threads = 0;          //!< 0: every core; the result does not depend on it
};

struct MultigridStats {
  std::vector<Eigen::Index> unknowns;  //!< per level, finest first
  std::vector<size_t> nonzeros;        //!< per level
  //! Σ non-zeros over the levels / the finest's: what one cycle costs in passes over the matrix
  double operator_complexity = 0;
  double bytes = 0;  //!< the coarse matrices, prolongations and restrictions, as stored
  double seconds_setup = 0;
};

//! The hierarchy of a matrix: aggregates of strongly connected unknowns, prolongations smoothed
//! by one damped Jacobi step, Galerkin coarse matrices PᵀAP, a Cholesky factor at the coarsest.
class Multigrid {
 public:
  //! \param A n by n, symmetric positive definite, both triangles stored, compressed
  //! \param near_null n by k: vectors A barely penalises, which the coarse levels must represent
  //!        (for a mesh's scaled system S⁻¹ times the constant and the coordinates); empty: ones
  //! \throw SolverError if the coarsest level cannot be factorised, InputError for bad shapes
  explicit Multigrid(const RowSparseMatrixd& A, const MultigridOptions& options = {}, const Eigen::MatrixXd& near_null = {});
  ~Multigrid();
  Multigrid(const Multigrid&) = delete;
  Multigrid& operator=(const Multigrid&) = delete;

  //! Z = one symmetric V-cycle applied to each column of R (n by K): Z ≈ A⁻¹R. As an operator
  //! it is symmetric positive definite, so CG may use it as its preconditioner. Not for two
  //! callers at once: the levels' work arrays are kept between calls (each call uses every core).
  void apply(const RowMatrixXd& R, RowMatrixXd& Z) const;
  const MultigridStats& stats() const { return stats_; }

 private:
  struct Level;
  struct Coarsest;
  void cycle(size_t level, const RowMatrixXd& b, RowMatrixXd& x) const;
  MultigridOptions options_;
  std::vector<Level> levels_;  // levels_[0] refers to the finest matrix, the caller's
  std::unique_ptr<Coarsest> coarsest_;
  MultigridStats stats_;
};

}  // namespace prtsub
