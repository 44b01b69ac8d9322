// Block conjugate gradients: K independent CG runs that share every pass over A.
//
// The least-squares fit's system, scaled to a unit diagonal, is the P1 mass matrix (whose scaled
// eigenvalues lie in [1/2, 2] on any mesh) plus α times a regulariser, so plain CG converges in
// a few dozen iterations where a Cholesky factorisation has to fill in a 3-D mesh's separators.
// Each iteration makes three passes over row blocks: Y = AP with pᵀAp; X, R updated with rᵀr;
// P = R + βP. With a preconditioner M (a multigrid cycle, multigrid.cpp), Z = M⁻¹R and rᵀz
// come between the last two and P = Z + βP; the residual norm still decides convergence. A
// preconditioner that inverts A's block on a few rows S and is the identity elsewhere
// (RowBlockInverse: the fit's stiff rows) needs no Z: rᵀz is rᵀr corrected on S, and the pass
// P = R + βP reads M⁻¹R's rows S from an |S| by K array. The matrix is row-major and the vectors are row-major #n by K, so a row of A
// reads K contiguous values per neighbour. Dot products are summed per fixed block of rows and
// then over blocks in order: the result is the same for any number of threads.
#include "prtsub/prt/block_cg.h"

#include "prtsub/prt/huge_pages.h"
#include "prtsub/prt/parallel.h"
#include "prtsub/subdiv/exceptions.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace prtsub {

void multiply_sparse_rows(const RowSparseMatrixd& A, const double* in, double* out, Eigen::Index K, Eigen::Index first,
                          Eigen::Index last, bool accumulate) {
  const auto* outer = A.outerIndexPtr();
  const auto* inner = A.innerIndexPtr();
  const double* value = A.valuePtr();
  for (Eigen::Index i = first; i < last; ++i) {
    double* o = out + i * K;
    if (!accumulate) std::fill(o, o + K, 0.0);
    for (auto k = outer[i]; k < outer[i + 1]; ++k) {
      const double v = value[k];
      const double* p = in + Eigen::Index(inner[k]) * K;
      for (Eigen::Index q = 0; q < K; ++q) o[q] += v * p[q];
    }
  }
}

namespace {

constexpr Eigen::Index kBlockRows = 1024;

struct Blocks {
  Eigen::Index n, K, count;
  int threads;
  std::vector<double> partial;  // count by K

  // body(first, last, partial row) for each block in parallel, then the column sums in order.
  template <class Body>
  std::vector<double> run(Body&& body) {
    std::fill(partial.begin(), partial.end(), 0.0);
    parallel_range(count, threads, Eigen::Index(1), [&](const tbb::blocked_range<Eigen::Index>& r) {
      for (Eigen::Index b = r.begin(); b < r.end(); ++b)
        body(b * kBlockRows, std::min(n, (b + 1) * kBlockRows), partial.data() + b * K);
    });
    std::vector<double> sum(static_cast<size_t>(K), 0.0);
    for (Eigen::Index b = 0; b < count; ++b)
      for (Eigen::Index q = 0; q < K; ++q) sum[size_t(q)] += partial[size_t(b * K + q)];
    return sum;
  }
};

// out = A·in for rows first..last-1; dot[q] += Σ in(i,q)·out(i,q) over those rows.
void multiply_rows(const RowSparseMatrixd& A, const double* in, double* out, Eigen::Index K, Eigen::Index first,
                   Eigen::Index last, double* dot) {
  multiply_sparse_rows(A, in, out, K, first, last);
  for (Eigen::Index i = first * K; i < last * K; ++i) dot[i % K] += in[i] * out[i];
}

// One block CG run: the state of K columns and the three passes of an iteration.
class Run {
 public:
  Run(const RowSparseMatrixd& A, RowMatrixXd& B, RowMatrixXd& X, const BlockCgOptions& o, const BlockPreconditioner& m,
      const RowBlockInverse* block = nullptr)
      : A_(A), R_(B), X_(X), o_(o), m_(m), block_(block && !block->rows.empty() ? block : nullptr), n_(A.rows()), K_(B.cols()), blocks_{n_, K_, (n_ + kBlockRows - 1) / kBlockRows, o.threads, {}},
        P_(n_, K_), Y_(n_, K_) {
    blocks_.partial.resize(size_t(blocks_.count * K_));
    prefer_huge_pages(P_), prefer_huge_pages(Y_);
  }

  // R = B − AX, in B's place (memory is what this costs most), P = R (or M⁻¹R), and the norms of B and R.
  // Returns whether any column has yet to converge.
  bool start() {
    const Eigen::Index K = K_;
    bb_ = blocks_.run([&](Eigen::Index f, Eigen::Index l, double* dot) {
      for (Eigen::Index i = f * K; i < l * K; ++i) dot[i % K] += R_.data()[i] * R_.data()[i];
    });
    blocks_.run([&](Eigen::Index f, Eigen::Index l, double* dot) { multiply_rows(A_, X_.data(), Y_.data(), K, f, l, dot); });
    rr_ = blocks_.run([&](Eigen::Index f, Eigen::Index l, double* dot) {
      for (Eigen::Index i = f * K; i < l * K; ++i) {
        R_.data()[i] -= Y_.data()[i];
        P_.data()[i] = R_.data()[i];
        dot[i % K] += R_.data()[i] * R_.data()[i];
      }
    });
    rz_ = rr_;
    if (m_) {
      rz_ = precondition();
      P_ = Z_;
    } else if (block_) {
      rz_ = precondition_block(rr_);
      for (size_t a = 0; a < block_->rows.size(); ++a) P_.row(block_->rows[a]) = ZS_.row(Eigen::Index(a));
    }
    const auto k = static_cast<size_t>(K);
    target_.resize(k), alpha_.resize(k), beta_.resize(k), active_.resize(k);
    bool any = false;
    for (size_t c = 0; c < k; ++c) {
      if (bb_[c] == 0) {  // the solution is zero
        X_.col(static_cast<Eigen::Index>(c)).setZero();
        rr_[c] = 0;
      }
      target_[c] = o_.tolerance * o_.tolerance * bb_[c];
      active_[c] = rr_[c] > target_[c];
      any |= active_[c] != 0;
    }
    history_.assign(1, worst());
    return any;
  }

  // One iteration on the active columns: Y = AP with pᵀAp, then X and R with rᵀr. Returns
  // false when a column breaks down (pᵀAp ≤ 0: A is not positive definite); sets `any` to
  // whether a column is still active.
  bool step(bool& any) {
    const Eigen::Index K = K_;
    std::vector<double> pap = blocks_.run(
        [&](Eigen::Index f, Eigen::Index l, double* dot) { multiply_rows(A_, P_.data(), Y_.data(), K, f, l, dot); });
    for (size_t c = 0; c < size_t(K); ++c) {
      alpha_[c] = 0;
      if (!active_[c]) continue;
      if (!(pap[c] > 0) || !std::isfinite(pap[c])) return false;
      alpha_[c] = rz_[c] / pap[c];
    }
    std::vector<double> next = blocks_.run([&](Eigen::Index f, Eigen::Index l, double* dot) {
      for (Eigen::Index i = f; i < l; ++i) {
        double* x = X_.data() + i * K;
        double* r = R_.data() + i * K;
        const double* p = P_.data() + i * K;
        const double* y = Y_.data() + i * K;
        for (Eigen::Index q = 0; q < K; ++q) {
          x[q] += alpha_[size_t(q)] * p[q];
          r[q] -= alpha_[size_t(q)] * y[q];
          dot[q] += r[q] * r[q];
        }
      }
    });
    const std::vector<double> next_rz = m_ ? precondition() : block_ ? precondition_block(next) : next;
    any = false;
    for (size_t c = 0; c < size_t(K); ++c) {
      beta_[c] = active_[c] && rz_[c] > 0 ? next_rz[c] / rz_[c] : 0;
      if (active_[c]) rr_[c] = next[c], rz_[c] = next_rz[c];
      active_[c] = active_[c] && rr_[c] > target_[c];
      any |= active_[c] != 0;
    }
    history_.push_back(worst());
    return true;
  }

  // Z = M⁻¹R; returns rᵀz per column.
  std::vector<double> precondition() {
    const Eigen::Index K = K_;
    m_(R_, Z_);
    return blocks_.run([&](Eigen::Index f, Eigen::Index l, double* dot) {
      for (Eigen::Index i = f * K; i < l * K; ++i) dot[i % K] += R_.data()[i] * Z_.data()[i];
    });
  }

  // Z = M⁻¹R on the block's rows, into ZS_ (column-major |S| by K); returns rᵀz per column from
  // rr, rᵀr over every row: off S, z = r. Summed over S in order: the same for any thread count.
  std::vector<double> precondition_block(const std::vector<double>& rr) {
    const std::vector<Eigen::Index>& S = block_->rows;
    const Eigen::Index K = K_, m = Eigen::Index(S.size());
    ZS_.resize(m, K);
    for (Eigen::Index a = 0; a < m; ++a) ZS_.row(a) = R_.row(S[size_t(a)]);
    std::vector<double> rz = rr;
    for (Eigen::Index q = 0; q < K; ++q) rz[size_t(q)] -= ZS_.col(q).squaredNorm();
    block_->solve(ZS_);
    for (Eigen::Index a = 0; a < m; ++a)
      for (Eigen::Index q = 0; q < K; ++q) rz[size_t(q)] += R_(S[size_t(a)], q) * ZS_(a, q);
    return rz;
  }

  // P = Z + βP on the active columns (Z = R without a preconditioner, and off the block's rows).
  void next_direction() {
    const Eigen::Index K = K_;
    const RowMatrixXd& Z = m_ ? Z_ : R_;
    const std::vector<Eigen::Index>* S = block_ ? &block_->rows : nullptr;
    blocks_.run([&](Eigen::Index f, Eigen::Index l, double*) {
      size_t a = S ? size_t(std::lower_bound(S->begin(), S->end(), f) - S->begin()) : 0;
      for (Eigen::Index i = f; i < l; ++i) {
        double* p = P_.data() + i * K;
        if (S && a < S->size() && (*S)[a] == i) {
          for (Eigen::Index q = 0; q < K; ++q)
            if (active_[size_t(q)]) p[q] = ZS_(Eigen::Index(a), q) + beta_[size_t(q)] * p[q];
          ++a;
          continue;
        }
        const double* z = Z.data() + i * K;
        for (Eigen::Index q = 0; q < K; ++q)
          if (active_[size_t(q)]) p[q] = z[q] + beta_[size_t(q)] * p[q];
      }
    });
  }

  // Whether the last 10 iterations' rate of decrease says max_iterations will not reach the
  // tolerance: a stiff system is better handed to a direct solver now than after the cap.
  bool stalling(int iterations) const {
    const int window = 10;
    if (!o_.predict_stall || iterations < 2 * window) return false;
    const double rate = std::pow(history_[size_t(iterations)] / history_[size_t(iterations - window)], 1.0 / window);
    const double needed = rate < 1 ? std::log(o_.tolerance / history_[size_t(iterations)]) / std::log(rate) : INFINITY;
    return iterations + needed > o_.max_iterations;
  }

  // The worst column's relative residual.
  double worst() const {
    double w = 0;
    for (size_t c = 0; c < bb_.size(); ++c)
      if (bb_[c] > 0) w = std::max(w, std::sqrt(rr_[c] / bb_[c]));
    return w;
  }

 private:
  const RowSparseMatrixd& A_;
  RowMatrixXd& R_;
  RowMatrixXd& X_;
  const BlockCgOptions& o_;
  const BlockPreconditioner& m_;
  const RowBlockInverse* block_;
  Eigen::Index n_, K_;
  Blocks blocks_;
  RowMatrixXd P_, Y_, Z_;
  Eigen::MatrixXd ZS_;  // M⁻¹R on the block's rows
  std::vector<double> bb_, rr_, rz_, target_, alpha_, beta_, history_;
  std::vector<char> active_;
};

}  // namespace

void check_block_rows(const std::vector<Eigen::Index>& rows, Eigen::Index n, const char* what) {
  for (size_t a = 0; a < rows.size(); ++a)
    if (rows[a] < 0 || rows[a] >= n || (a > 0 && rows[a] <= rows[a - 1]))
      throw InputError(std::string(what) + " rows must be ascending indices of the matrix");
}

namespace {

BlockCgResult solve(const RowSparseMatrixd& A_in, RowMatrixXd& B, RowMatrixXd& X, const BlockCgOptions& o, const BlockPreconditioner& m,
                    const RowBlockInverse* block) {
  BlockCgResult result;
  if (A_in.rows() == 0 || B.cols() == 0) {
    result.converged = true;
    return result;
  }
  // The passes read the compressed arrays (outer[i]..outer[i+1]); a matrix still being filled
  // has reserved, unwritten slots between its rows, so take a compressed copy of it.
  RowSparseMatrixd compressed;
  if (!A_in.isCompressed()) compressed = A_in, compressed.makeCompressed();
  const RowSparseMatrixd& A = A_in.isCompressed() ? A_in : compressed;
  Run run(A, B, X, o, m, block);
  bool any = run.start(), broke = false;
  while (any && result.iterations < o.max_iterations) {
    if (!run.step(any)) {
      broke = true;
      break;
    }
    ++result.iterations;
    if (!any) break;
    if (run.stalling(result.iterations)) {
      result.predicted_stall = true;
      break;
    }
    run.next_direction();
  }
  result.converged = !any && !broke;
  result.relative_residual = run.worst();
  return result;
}

}  // namespace

BlockCgResult block_conjugate_gradient(const RowSparseMatrixd& A, RowMatrixXd B, RowMatrixXd& X, const BlockCgOptions& o,
                                       const BlockPreconditioner& m) {
  return solve(A, B, X, o, m, nullptr);
}

BlockCgResult block_conjugate_gradient(const RowSparseMatrixd& A, RowMatrixXd B, RowMatrixXd& X, const BlockCgOptions& o,
                                       const RowBlockInverse& block) {
  check_block_rows(block.rows, A.rows(), "block CG: the preconditioner's");
  if (!block.rows.empty() && !block.solve) throw InputError("block CG: the preconditioner's block has no solve");
  return solve(A, B, X, o, {}, &block);
}

}  // namespace prtsub
