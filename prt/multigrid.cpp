// Smoothed-aggregation algebraic multigrid (Vaněk, Mandel, Brezina 1996) as CG's preconditioner.
//
// Why: the fit's system, Jacobi-scaled, is the mass matrix (eigenvalues in [1/2, 2] on any mesh)
// plus α times a regulariser whose entries do not shrink with the faces. Where the regulariser
// outweighs the mass, as on a refined mesh (each level quarters the areas) or beside slivers, the
// smooth functions it barely penalises have tiny eigenvalues and CG's iterations grow with every
// level. A multigrid cycle removes the smooth error on coarser levels, where it is no longer
// smooth, so the iterations stay flat.
//
// Setup, level by level until one has at most `coarsest` unknowns:
//  - Strong neighbours: |a_ij| ≥ θ√(a_ii a_jj).
//  - Aggregates, in three passes over the unknowns in their order (the fit numbers them
//    breadth-first, so aggregates are compact): an unknown whose strong neighbours are all free
//    starts an aggregate of itself and them; a left-over unknown joins the aggregate it is most
//    strongly connected to; what is still left groups with its free strong neighbours.
//  - The tentative prolongation P₀ holds each aggregate's normalised constant; one damped
//    Jacobi step smooths it, P = (I − ω D⁻¹A) P₀ with ω = 4/(3ρ), ρ the spectral radius of D⁻¹A
//    from a few power iterations: smoothed, P carries linear functions far better than
//    constants per aggregate do.
//  - The coarse matrix is PᵀAP (symmetrised against round-off), restriction is Pᵀ stored row-major.
//  - The coarsest level is factorised by a simplicial Cholesky.
// The cycle is a V-cycle with the same number of damped Jacobi steps before and after the coarse
// correction, so it is a symmetric positive definite operator, as CG requires. Every row is
// computed by one worker in a fixed order, and the setup's sums are sequential: the result is
// the same for any number of threads.
#include "prtsub/prt/multigrid.h"

#include <Eigen/QR>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <utility>

#include "prtsub/prt/huge_pages.h"
#include "prtsub/prt/parallel.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {

struct Multigrid::Level {
  const RowSparseMatrixd* A = nullptr;  // this level's matrix (owned below for coarse levels)
  RowSparseMatrixd owned;
  Eigen::VectorXd inverse_diagonal;     // ω / a_ii: the damped Jacobi step
  RowSparseMatrixd prolongation;        // n by n_coarse (empty at the coarsest)
  RowSparseMatrixd restriction;         // its transpose, row-major
  // A cycle's work arrays, kept between cycles: fresh arrays would cost their first-touch page
  // faults every time (they dominated a profile of the cycle on refined bunny).
  mutable RowMatrixXd residual, coarse_rhs, coarse_x;
};

struct Multigrid::Coarsest {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
};

namespace {

constexpr Eigen::Index kGrain = 2048;

// out = M·in (row-major #rows by K); or out += M·in.
void multiply(const RowSparseMatrixd& M, const RowMatrixXd& in, RowMatrixXd& out, int threads, bool accumulate = false) {
  const Eigen::Index K = in.cols();
  if (!accumulate && (out.rows() != M.rows() || out.cols() != K)) out.resize(M.rows(), K), prefer_huge_pages(out);
  parallel_range(M.rows(), threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& r) {
    multiply_sparse_rows(M, in.data(), out.data(), K, r.begin(), r.end(), accumulate);
  });
}

// ρ(D⁻¹A) by power iteration from a fixed start: D⁻¹A is similar to D^-½AD^-½, whose largest
// eigenvalue the Rayleigh quotient approaches from below; 1.1 × the estimate covers the rest.
double spectral_radius(const RowSparseMatrixd& A, const Eigen::VectorXd& d) {
  const Eigen::Index n = A.rows();
  const Eigen::VectorXd s = d.cwiseSqrt().cwiseInverse();
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = 1.0 + 0.5 * std::sin(0.7 * double(i));  // not an eigenvector
  double rho = 0;
  for (int it = 0; it < 12; ++it) {
    v /= v.norm();
    const Eigen::VectorXd w = s.asDiagonal() * (A * (s.asDiagonal() * v));
    rho = v.dot(w);
    v = w;
  }
  return 1.1 * rho;
}

// Aggregates of strongly connected unknowns: aggregate[i] for each unknown; returns their count.
Eigen::Index aggregate(const RowSparseMatrixd& A, const Eigen::VectorXd& d, double theta, std::vector<Eigen::Index>& agg) {
  const Eigen::Index n = A.rows();
  auto strong = [&](Eigen::Index i, Eigen::Index j, double v) { return j != i && std::abs(v) >= theta * std::sqrt(std::abs(d[i] * d[j])); };
  agg.assign(size_t(n), -1);
  Eigen::Index count = 0;
  // Pass 1: roots whose strong neighbourhood is entirely free.
  for (Eigen::Index i = 0; i < n; ++i) {
    if (agg[size_t(i)] >= 0) continue;
    bool free = true, any = false;
    for (RowSparseMatrixd::InnerIterator it(A, i); it && free; ++it)
      if (strong(i, it.col(), it.value())) any = true, free = agg[size_t(it.col())] < 0;
    if (!free || !any) continue;
    agg[size_t(i)] = count;
    for (RowSparseMatrixd::InnerIterator it(A, i); it; ++it)
      if (strong(i, it.col(), it.value())) agg[size_t(it.col())] = count;
    ++count;
  }
  // Pass 2: the rest join the aggregate they are most strongly connected to (ties: the first).
  std::vector<Eigen::Index> joined(agg);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (agg[size_t(i)] >= 0) continue;
    double best = 0;
    for (RowSparseMatrixd::InnerIterator it(A, i); it; ++it) {
      const double w = std::abs(it.value()) / std::sqrt(std::abs(d[i] * d[it.col()]));
      if (strong(i, it.col(), it.value()) && agg[size_t(it.col())] >= 0 && w > best) best = w, joined[size_t(i)] = agg[size_t(it.col())];
    }
  }
  agg.swap(joined);
  // Pass 3: whatever is left (no strong link to an aggregate) groups with its free strong
  // neighbours, or stands alone.
  for (Eigen::Index i = 0; i < n; ++i) {
    if (agg[size_t(i)] >= 0) continue;
    agg[size_t(i)] = count;
    for (RowSparseMatrixd::InnerIterator it(A, i); it; ++it)
      if (strong(i, it.col(), it.value()) && agg[size_t(it.col())] < 0) agg[size_t(it.col())] = count;
    ++count;
  }
  return count;
}

// P₀: on each aggregate, an orthonormal basis of the near-null vectors B restricted to it (a
// column-pivoted QR, dropping directions the aggregate cannot tell apart); the coarse level's
// near-null vectors are the QR's R factors, so that P₀ B_coarse = B.
RowSparseMatrixd tentative_prolongation(const std::vector<Eigen::Index>& agg, Eigen::Index count, const Eigen::MatrixXd& B,
                                        Eigen::MatrixXd& coarse_B) {
  const Eigen::Index n = Eigen::Index(agg.size()), k = B.cols();
  std::vector<Eigen::Index> begin(static_cast<size_t>(count) + 1, 0), member(static_cast<size_t>(n));
  for (Eigen::Index a : agg) ++begin[size_t(a) + 1];
  for (size_t a = 0; a < size_t(count); ++a) begin[a + 1] += begin[a];
  {
    std::vector<Eigen::Index> next(begin.begin(), begin.end() - 1);
    for (Eigen::Index i = 0; i < n; ++i) member[size_t(next[size_t(agg[size_t(i)])]++)] = i;
  }
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(size_t(n * k));
  std::vector<Eigen::MatrixXd> coarse_rows;
  Eigen::Index columns = 0;
  for (Eigen::Index a = 0; a < count; ++a) {
    const Eigen::Index first = begin[size_t(a)], m = begin[size_t(a) + 1] - first;
    Eigen::MatrixXd local(m, k);
    for (Eigen::Index r = 0; r < m; ++r) local.row(r) = B.row(member[size_t(first + r)]);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(local);
    qr.setThreshold(1e-8);
    const Eigen::Index rank = std::max<Eigen::Index>(qr.rank(), 1);
    const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(m, rank);
    const Eigen::MatrixXd upper = qr.matrixR().topRows(rank).triangularView<Eigen::Upper>();
    const Eigen::MatrixXd R = upper * qr.colsPermutation().transpose();
    for (Eigen::Index r = 0; r < m; ++r)
      for (Eigen::Index c = 0; c < rank; ++c) entries.emplace_back(member[size_t(first + r)], columns + c, Q(r, c));
    coarse_rows.push_back(R);
    columns += rank;
  }
  coarse_B.resize(columns, k);
  Eigen::Index row = 0;
  for (const Eigen::MatrixXd& R : coarse_rows) coarse_B.middleRows(row, R.rows()) = R, row += R.rows();
  RowSparseMatrixd P0(n, columns);
  P0.setFromTriplets(entries.begin(), entries.end());
  return P0;
}

// P = (I − ω D⁻¹A) P₀, row by row.
RowSparseMatrixd smoothed_prolongation(const RowSparseMatrixd& A, const Eigen::VectorXd& damped_inverse_diagonal,
                                       const RowSparseMatrixd& P0, int threads) {
  const Eigen::Index n = A.rows();
  std::vector<std::vector<std::pair<Eigen::Index, double>>> rows(static_cast<size_t>(n));
  parallel_range(n, threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& r) {
    std::vector<std::pair<Eigen::Index, double>> terms;
    for (Eigen::Index i = r.begin(); i < r.end(); ++i) {
      terms.clear();
      for (RowSparseMatrixd::InnerIterator p(P0, i); p; ++p) terms.emplace_back(p.col(), p.value());
      for (RowSparseMatrixd::InnerIterator it(A, i); it; ++it)
        for (RowSparseMatrixd::InnerIterator p(P0, it.col()); p; ++p)
          terms.emplace_back(p.col(), -damped_inverse_diagonal[i] * it.value() * p.value());
      // Sum equal columns in a fixed order (a stable sort keeps the row's order within each).
      std::stable_sort(terms.begin(), terms.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
      auto& row = rows[size_t(i)];
      for (const auto& t : terms)
        if (!row.empty() && row.back().first == t.first) row.back().second += t.second;
        else row.push_back(t);
    }
  });
  RowSparseMatrixd P(n, P0.cols());
  Eigen::VectorXi per_row(n);
  for (Eigen::Index i = 0; i < n; ++i) per_row[i] = int(rows[size_t(i)].size());
  P.reserve(per_row);
  for (Eigen::Index i = 0; i < n; ++i)
    for (const auto& [a, v] : rows[size_t(i)])
      if (v != 0) P.insert(i, a) = v;
  P.makeCompressed();
  return P;
}

}  // namespace

Multigrid::~Multigrid() = default;

Multigrid::Multigrid(const RowSparseMatrixd& A, const MultigridOptions& options, const Eigen::MatrixXd& near_null)
    : options_(options) {
  Eigen::MatrixXd B = near_null.size() ? near_null : Eigen::MatrixXd::Ones(A.rows(), 1);
  if (B.rows() != A.rows()) throw InputError("multigrid: the near-null vectors do not match the matrix");
  const Stopwatch clock;
  levels_.reserve(size_t(std::max(options_.max_levels, 1)));  // no reallocation: levels point at each other's matrices
  levels_.emplace_back();
  levels_.back().A = &A;
  for (;;) {
    Level& level = levels_.back();
    const RowSparseMatrixd& M = *level.A;
    const Eigen::VectorXd d = M.diagonal();
    if (!(d.minCoeff() > 0)) throw SolverError("multigrid: the matrix has a non-positive diagonal");
    const double omega = 4.0 / (3.0 * spectral_radius(M, d));
    level.inverse_diagonal = omega * d.cwiseInverse();
    stats_.unknowns.push_back(M.rows());
    stats_.nonzeros.push_back(size_t(M.nonZeros()));
    if (M.rows() <= options_.coarsest || int(levels_.size()) >= options_.max_levels) break;
    std::vector<Eigen::Index> agg;
    const Eigen::Index count = aggregate(M, d, options_.strength, agg);
    if (count * 5 > M.rows() * 4) break;  // coarsening has stalled: solve here
    Eigen::MatrixXd coarse_B;
    const RowSparseMatrixd P0 = tentative_prolongation(agg, count, B, coarse_B);
    if (P0.cols() * 5 > M.rows() * 4) break;
    B = std::move(coarse_B);
    level.prolongation = smoothed_prolongation(M, level.inverse_diagonal, P0, options_.threads);
    level.restriction = level.prolongation.transpose();
    RowSparseMatrixd AP = M * level.prolongation;
    RowSparseMatrixd coarse = level.restriction * AP;
    RowSparseMatrixd coarse_t = coarse.transpose();
    Level next;
    next.owned = 0.5 * (coarse + coarse_t);
    next.owned.makeCompressed();
    levels_.push_back(std::move(next));
    levels_.back().A = &levels_.back().owned;
  }
  coarsest_ = std::make_unique<Coarsest>();
  const Eigen::SparseMatrix<double> last = *levels_.back().A;
  coarsest_->factor.compute(last);
  if (coarsest_->factor.info() != Eigen::Success) throw SolverError("multigrid: the coarsest level is not positive definite");
  double total = 0;
  for (size_t z : stats_.nonzeros) total += double(z);
  auto stored = [](const RowSparseMatrixd& m) { return 12.0 * double(m.nonZeros()) + 4.0 * double(m.rows() + 1); };
  for (const Level& l : levels_) stats_.bytes += stored(l.owned) + stored(l.prolongation) + stored(l.restriction);
  stats_.operator_complexity = total / double(stats_.nonzeros.front());
  stats_.seconds_setup = clock.total();
}

void Multigrid::cycle(size_t l, const RowMatrixXd& b, RowMatrixXd& x) const {
  const Level& level = levels_[l];
  const int threads = options_.threads;
  const Eigen::Index n = b.rows(), K = b.cols();
  if (x.rows() != n || x.cols() != K) x.resize(n, K), prefer_huge_pages(x);
  if (l + 1 == levels_.size()) {
    Eigen::MatrixXd solved = coarsest_->factor.solve(Eigen::MatrixXd(b));
    x = solved;
    return;
  }
  const RowSparseMatrixd& A = *level.A;
  const Eigen::VectorXd& w = level.inverse_diagonal;
  RowMatrixXd& r = level.residual;
  if (r.rows() != n || r.cols() != K) r.resize(n, K), prefer_huge_pages(r);
  // x += ωD⁻¹(b − Ax), from x = 0 for the first step; with `residual`, r = b − Ax after it.
  auto smooth = [&](bool from_zero, bool residual) {
    if (!from_zero) multiply(A, x, r, threads);
    parallel_range(n, threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& rg) {
      for (Eigen::Index i = rg.begin(); i < rg.end(); ++i) {
        double* xi = x.data() + i * K;
        const double* bi = b.data() + i * K;
        const double* ri = r.data() + i * K;
        for (Eigen::Index q = 0; q < K; ++q) xi[q] = from_zero ? w[i] * bi[q] : xi[q] + w[i] * (bi[q] - ri[q]);
      }
    });
    if (!residual) return;
    multiply(A, x, r, threads);
    parallel_range(n, threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& rg) {
      for (Eigen::Index i = rg.begin() * K; i < rg.end() * K; ++i) r.data()[i] = b.data()[i] - r.data()[i];
    });
  };
  const int steps = std::max(options_.smoothing_steps, 1);
  for (int s = 0; s < steps; ++s) smooth(s == 0, s + 1 == steps);
  multiply(level.restriction, r, level.coarse_rhs, threads);
  cycle(l + 1, level.coarse_rhs, level.coarse_x);
  multiply(level.prolongation, level.coarse_x, x, threads, true);
  for (int s = 0; s < steps; ++s) smooth(false, false);
}

void Multigrid::apply(const RowMatrixXd& R, RowMatrixXd& Z) const { cycle(0, R, Z); }

}  // namespace prtsub
