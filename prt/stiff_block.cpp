// A stiff block: the rows whose diagonal the regulariser holds almost alone, solved together.
//
// Why: the fit's system, scaled to a unit diagonal, is the mass matrix (eigenvalues in [1/2, 2])
// plus α times a regulariser. Where a row's mass is a small share of its diagonal (a sliver
// beside a large face, a degenerate face of a scan), the regulariser's smooth functions over a
// run of such rows have eigenvalues near zero, and Jacobi-scaled CG stalls on them: on sibenik
// refined once (18% of its rows stiff) it gave up after 20 iterations. Their block couples only
// along the slivers, so its Cholesky factor stays small (a tenth of the system's entries there).
// With the block inverted exactly and the identity elsewhere, what CG still sees is the rows the
// mass holds, conditioned like the mass itself. It is block Jacobi with one block: symmetric and
// positive definite, as CG requires, and the same for any thread count (the factor is computed
// once).
#include "prtsub/prt/stiff_block.h"

#include <Eigen/CholmodSupport>
#include <algorithm>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

struct StiffBlock::Factor {
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
};

StiffBlock::StiffBlock(const RowSparseMatrixd& A, std::vector<Eigen::Index> rows) : rows_(std::move(rows)), factor_(std::make_unique<Factor>()) {
  const Eigen::Index n = A.rows(), m = Eigen::Index(rows_.size());
  check_block_rows(rows_, n, "stiff block:");
  std::vector<Eigen::Index> slot(size_t(n), -1);
  for (Eigen::Index a = 0; a < m; ++a) slot[size_t(rows_[size_t(a)])] = a;
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index a = 0; a < m; ++a)
    for (RowSparseMatrixd::InnerIterator it(A, rows_[size_t(a)]); it; ++it) {
      const Eigen::Index b = slot[size_t(it.col())];
      if (b >= 0 && b >= a) t.emplace_back(b, a, it.value());  // row ≥ column: the lower triangle
    }
  block_.resize(m, m);
  block_.setFromTriplets(t.begin(), t.end());
  if (m == 0) return;
  factor_->llt.cholmod().print = 0;  // failures are the caller's to report
  factor_->llt.analyzePattern(block_);
  predicted_entries_ = size_t(factor_->llt.cholmod().lnz);
}

StiffBlock::~StiffBlock() = default;

bool StiffBlock::factorise() {
  if (rows_.empty()) return factored_ = true;
  factor_->llt.factorize(block_);
  factored_ = factor_->llt.info() == Eigen::Success;
  return factored_;
}

RowBlockInverse StiffBlock::inverse() const {
  if (!factored_) throw SolverError("stiff block: not factorised");
  RowBlockInverse r;
  r.rows = rows_;
  const Factor* f = factor_.get();
  r.solve = [f](Eigen::MatrixXd& block) { block = f->llt.solve(block); };
  return r;
}

}  // namespace prtsub
