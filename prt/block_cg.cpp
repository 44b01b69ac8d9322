// Block conjugate gradients: K independent CG runs that share every pass over A.
//
// The least-squares fit's system, scaled to a unit diagonal, is the P1 mass matrix (whose scaled
// eigenvalues lie in [1/2, 2] on any mesh) plus α times a regulariser, so plain CG converges in
// a few dozen iterations where a Cholesky factorisation has to fill in a 3-D mesh's separators.
// Each iteration makes three passes over row blocks: Y = AP with pᵀAp; X, R updated with rᵀr;
// P = R + βP. The matrix is row-major and the vectors are row-major #n by K, so a row of A
// reads K contiguous values per neighbour. Dot products are summed per fixed block of rows and
// then over blocks in order: the result is the same for any number of threads.
#include "prtsub/prt/block_cg.h"

#include "prtsub/prt/parallel.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace prtsub {
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
  const auto* outer = A.outerIndexPtr();
  const auto* inner = A.innerIndexPtr();
  const double* value = A.valuePtr();
  for (Eigen::Index i = first; i < last; ++i) {
    double* o = out + i * K;
    std::fill(o, o + K, 0.0);
    for (auto k = outer[i]; k < outer[i + 1]; ++k) {
      const double v = value[k];
      const double* p = in + Eigen::Index(inner[k]) * K;
      for (Eigen::Index q = 0; q < K; ++q) o[q] += v * p[q];
    }
    const double* p = in + i * K;
    for (Eigen::Index q = 0; q < K; ++q) dot[q] += p[q] * o[q];
  }
}

}  // namespace

BlockCgResult block_conjugate_gradient(const RowSparseMatrixd& A, RowMatrixXd B, RowMatrixXd& X, const BlockCgOptions& o) {
  const Eigen::Index n = A.rows(), K = B.cols();
  BlockCgResult result;
  if (n == 0 || K == 0) {
    result.converged = true;
    return result;
  }
  Blocks blocks{n, K, (n + kBlockRows - 1) / kBlockRows, o.threads, {}};
  blocks.partial.resize(size_t(blocks.count * K));
  RowMatrixXd P(n, K), Y(n, K);

  // R = B − AX, in B's place (memory is what this costs most), and the norms of B and R.
  std::vector<double> bb = blocks.run([&](Eigen::Index f, Eigen::Index l, double* dot) {
    for (Eigen::Index i = f * K; i < l * K; ++i) dot[i % K] += B.data()[i] * B.data()[i];
  });
  RowMatrixXd& R = B;
  blocks.run([&](Eigen::Index f, Eigen::Index l, double* dot) { multiply_rows(A, X.data(), Y.data(), K, f, l, dot); });
  std::vector<double> rr = blocks.run([&](Eigen::Index f, Eigen::Index l, double* dot) {
    for (Eigen::Index i = f * K; i < l * K; ++i) {
      R.data()[i] -= Y.data()[i];
      P.data()[i] = R.data()[i];
      dot[i % K] += R.data()[i] * R.data()[i];
    }
  });

  const auto k = static_cast<size_t>(K);
  std::vector<double> target(k), alpha(k), beta(k);
  std::vector<char> active(k);
  auto worst = [&]() {
    double w = 0;
    for (Eigen::Index q = 0; q < K; ++q)
      if (bb[size_t(q)] > 0) w = std::max(w, std::sqrt(rr[size_t(q)] / bb[size_t(q)]));
    return w;
  };
  bool any = false;
  for (Eigen::Index q = 0; q < K; ++q) {
    const size_t c = size_t(q);
    if (bb[c] == 0) {  // the solution is zero
      X.col(q).setZero();
      rr[c] = 0;
    }
    target[c] = o.tolerance * o.tolerance * bb[c];
    active[c] = rr[c] > target[c];
    any |= active[c] != 0;
  }
  bool broke = false;
  std::vector<double> history{worst()};  // the worst column's relative residual, per iteration
  while (any && result.iterations < o.max_iterations) {
    std::vector<double> pap = blocks.run(
        [&](Eigen::Index f, Eigen::Index l, double* dot) { multiply_rows(A, P.data(), Y.data(), K, f, l, dot); });
    for (size_t c = 0; c < size_t(K); ++c) {
      alpha[c] = 0;
      if (!active[c]) continue;
      if (!(pap[c] > 0) || !std::isfinite(pap[c])) broke = true;
      else alpha[c] = rr[c] / pap[c];
    }
    if (broke) break;
    std::vector<double> next = blocks.run([&](Eigen::Index f, Eigen::Index l, double* dot) {
      for (Eigen::Index i = f; i < l; ++i) {
        double* x = X.data() + i * K;
        double* r = R.data() + i * K;
        const double* p = P.data() + i * K;
        const double* y = Y.data() + i * K;
        for (Eigen::Index q = 0; q < K; ++q) {
          x[q] += alpha[size_t(q)] * p[q];
          r[q] -= alpha[size_t(q)] * y[q];
          dot[q] += r[q] * r[q];
        }
      }
    });
    any = false;
    for (size_t c = 0; c < size_t(K); ++c) {
      beta[c] = active[c] && rr[c] > 0 ? next[c] / rr[c] : 0;
      if (active[c]) rr[c] = next[c];
      active[c] = active[c] && rr[c] > target[c];
      any |= active[c] != 0;
    }
    ++result.iterations;
    if (!any) break;
    // Give up early when the recent rate of decrease says the cap will not be enough: a stiff
    // system is better handed to a direct solver now than after max_iterations passes.
    history.push_back(worst());
    const int it = result.iterations, window = 10;
    if (o.predict_stall && it >= 2 * window) {
      const double rate = std::pow(history[size_t(it)] / history[size_t(it - window)], 1.0 / window);
      const double needed = rate < 1 ? std::log(o.tolerance / history[size_t(it)]) / std::log(rate) : INFINITY;
      if (it + needed > o.max_iterations) {
        result.predicted_stall = true;
        break;
      }
    }
    blocks.run([&](Eigen::Index f, Eigen::Index l, double*) {
      for (Eigen::Index i = f; i < l; ++i) {
        double* p = P.data() + i * K;
        const double* r = R.data() + i * K;
        for (Eigen::Index q = 0; q < K; ++q)
          if (active[size_t(q)]) p[q] = r[q] + beta[size_t(q)] * p[q];
      }
    });
  }
  result.converged = !any && !broke;
  result.relative_residual = worst();
  return result;
}

}  // namespace prtsub
