// Shadowed transfer with a cross-fitted control variate.
//
// For a point p with normal n, cosine-weighted directions ω_k (pdf cos/π) give the plain
// estimate (π/R) Σ V_k y(ω_k). The closed-form unshadowed transfer t_u(n) = ∫ cos⁺ y is a
// control variate: for any β independent of the samples it averages over,
//     t̂ = β t_u + (π/R) Σ (V_k − β) y(ω_k)
// is unbiased. β = 1 estimates only the blocked part (exact when nothing is blocked); β = 0
// estimates only the visible part (exact when everything is). We split the R rays into two
// halves, each its own lattice with its own independent random shift, and give each half the
// β chosen from the *other* half's visible fraction (1 if at least half visible, else 0).
// Independence matters: with one shared shift the halves' directions are correlated and the
// choice biases the estimate (the statistical test in transfer_test.cpp caught exactly that).
// With it, t̂ is unbiased; an unoccluded point is exact at any ray count, a fully enclosed one
// is exactly zero from two rays up, and SH are evaluated only for rays with V_k ≠ β — the
// minority — which keeps the stage close to a bare occlusion loop. With a single ray there
// is no other half and β = 1.
//
// Directions come from rank-1 lattices chosen by Zaremba's index (Fibonacci-like for any size),
// shifted by hashes of (seed, point's stream, half): decorrelated between points and identical
// for any thread count. A lattice can be doubled, the new lattice containing the old one
// (sampling.h; after a doubling it may no longer be rank-1), so a later round of rays at a vertex
// (vertex_top_up) fills in its first round's strata instead of adding an independent set. One
// point's rays go to Embree as one stream (rtcOccluded1M), which STACK.md measured 20-45% faster
// than single rays.
//
// Other estimators, for comparison (docs/transfer.md, BENCHMARKS.md "Estimators"): plain Monte
// Carlo projection over independent directions, and the progressive least-squares encoder of
// paper 004 (progressive_encoder.h) on a uniform sphere, over the whole integrand or only its
// blocked part against the same closed-form unshadowed transfer.
//
// Points can also be traced in consecutive groups that a callback consumes as soon as a group is
// done (shadowed_transfer_groups): the fit reduces each group of surface samples to its face's
// moments and never stores per-sample transfer. A group is traced by one thread, in order.
#include "prtsub/prt/transfer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>

#include "prtsub/prt/parallel.h"
#include "prtsub/prt/progressive_encoder.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/sg_basis.h"
#include "prtsub/prt/sh.h"
#include "prtsub/prt/trace_log.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

constexpr Eigen::Index kGrain = 16;  // points per task: small enough to balance, large enough to amortise

// Each half's doubling lattice (sampling.h): ray k of a call is ray first + k of its point's
// sequence, in half (first + k) & 1, point (first + k) >> 1 of that half's lattice.
struct RaySequence {
  uint32_t first = 0;
  uint32_t base[2] = {0, 0};
  DoublingLattice lattices[2];
  LatticeTable lattice;  // ray k's lattice point, unshifted: the same at every point of a call
};

RaySequence ray_sequence(const TransferOptions& o) {
  RaySequence q;
  q.first = o.first_ray;
  const auto R = static_cast<uint64_t>(o.rays);
  int doublings = 0;
  if (o.first_round_rays == 0) {
    if (o.first_ray != 0) throw InputError("a later round of rays needs the first round's count");
    q.base[0] = uint32_t((R + 1) / 2), q.base[1] = uint32_t(R / 2);
  } else {
    // Rays first_ray .. end − 1 of the sequence whose lattices have R0·2^j points: the round
    // starts at 0 or at such a count and ends at one.
    const auto R0 = static_cast<uint64_t>(o.first_round_rays);
    const uint64_t end = o.first_ray + R;
    uint64_t at = R0;
    while (at < end) at *= 2, ++doublings;
    const uint64_t start = o.first_ray / std::max<uint64_t>(R0, 1);
    const bool fits = R0 >= 2 && R0 % 2 == 0 && at == end &&
                      (o.first_ray == 0 || (o.first_ray % R0 == 0 && (start & (start - 1)) == 0));
    if (!fits)
      throw InputError("a later round of rays must run from the first round's count (even) times 2^j to times 2^k, got rays " +
                       std::to_string(o.first_ray) + " to " + std::to_string(end) + " after a first round of " + std::to_string(R0));
    q.base[0] = q.base[1] = uint32_t(R0 / 2);
  }
  q.lattices[0] = doubling_lattice(q.base[0], doublings);
  q.lattices[1] = q.base[1] == q.base[0] ? q.lattices[0] : doubling_lattice(q.base[1], doublings);  // the same lattice, once
  if (o.estimator != TransferEstimator::MonteCarlo)
    for (uint64_t k = 0; k < R; ++k) {
      const uint64_t g = q.first + k, h = g & 1;
      q.lattice.push_back(doubling_lattice_point(uint32_t(g >> 1), q.lattices[h]));
    }
  return q;
}

uint64_t point_stream(const TransferOptions& o, Eigen::Index i) {
  return o.streams ? (*o.streams)[static_cast<size_t>(i)] : o.stream_offset + static_cast<uint64_t>(i);
}

struct PointRays {
  std::vector<RTCRay> rays;
  std::vector<Eigen::Vector3d> directions;  // world, double: used for SH
};

// Fills the R rays of point i and traces them; afterwards rays[k].tfar == -inf if occluded.
void trace_point(const RayScene& scene, const RowMatrixX3d& points, const RowMatrixX3d& normals,
                 const RowMatrixX3d* offsets, Eigen::Index i, const TransferOptions& opt, const RaySequence& seq, PointRays& buf) {
  const uint32_t R = static_cast<uint32_t>(opt.rays);
  buf.rays.resize(R);
  buf.directions.resize(R);
  Eigen::Vector3d n = normals.row(i).transpose(), t, b;
  tangent_frame(n, t, b);
  Eigen::Vector3f local = scene.to_local(points.row(i).transpose());
  const Eigen::Vector3d away = offsets ? Eigen::Vector3d(offsets->row(i).transpose()) : n;
  Eigen::Vector3f origin = local + scene.ray_offset(local) * away.cast<float>();
  const uint64_t stream = point_stream(opt, i);
  Rng rng(opt.seed, stream);
  const double shift[2][2] = {{rng.uniform(), rng.uniform()}, {rng.uniform(), rng.uniform()}};
  const LatticeShift turn[2] = {LatticeShift(shift[0][0], shift[0][1]), LatticeShift(shift[1][0], shift[1][1])};
  // Plain Monte Carlo draws independent directions instead, from a stream of their own; a later
  // round skips the draws of the rays before it.
  Rng independent(opt.seed ^ 0x5D1A7E6C0FFEE123ull, stream);
  if (opt.estimator == TransferEstimator::MonteCarlo)
    for (uint64_t k = 0; k < 2ull * seq.first; ++k) independent.next();
  const bool uniform = opt.estimator == TransferEstimator::Progressive || opt.estimator == TransferEstimator::ProgressiveBlocked;
  for (uint32_t k = 0; k < R; ++k) {
    Eigen::Vector3d d;
    if (opt.estimator == TransferEstimator::MonteCarlo) {
      const double u = independent.uniform();
      d = cosine_direction(u, independent.uniform());
    } else {
      d = shifted_direction(seq.lattice, k, turn[(seq.first + k) & 1], uniform);
    }
    Eigen::Vector3d w = (d.x() * t + d.y() * b + d.z() * n).normalized();
    buf.directions[k] = w;
    init_occlusion_ray(buf.rays[k], origin, w.cast<float>());
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded1M(scene.handle(), &context, buf.rays.data(), R, sizeof(RTCRay));
}

inline bool occluded(const RTCRay& r) { return r.tfar == -std::numeric_limits<float>::infinity(); }

}  // namespace

const char* estimator_name(TransferEstimator e) {
  switch (e) {
    case TransferEstimator::ControlVariate: return "cv";
    case TransferEstimator::MonteCarlo: return "mc";
    case TransferEstimator::Progressive: return "pls";
    case TransferEstimator::ProgressiveBlocked: return "pls-cv";
  }
  return "?";
}

TransferEstimator estimator_from_name(const std::string& name) {
  for (TransferEstimator e : {TransferEstimator::ControlVariate, TransferEstimator::MonteCarlo, TransferEstimator::Progressive,
                              TransferEstimator::ProgressiveBlocked})
    if (name == estimator_name(e)) return e;
  throw InputError("estimator must be cv, mc, pls or pls-cv, got '" + name + "'");
}

void check_transfer_options(const TransferOptions& o) {
  if (o.order < 1 || o.order > kMaxShOrder)
    throw InputError("SH order must be between 1 and " + std::to_string(kMaxShOrder) + ", got " + std::to_string(o.order));
  if (o.rays < 1 || o.rays > (1 << 20))
    throw InputError("rays per point must be between 1 and 1048576, got " + std::to_string(o.rays));
  if (o.threads < 0) throw InputError("thread count must be 0 (every core) or more, got " + std::to_string(o.threads));
  if (o.progressive.non_negative)
    throw InputError("non-negative encoding is for bases of non-negative lobes; SH transfer coefficients are signed");
  if (!(o.progressive.acceleration > 0) || !std::isfinite(o.progressive.acceleration))
    throw InputError("the progressive encoder's acceleration must be positive, got " + std::to_string(o.progressive.acceleration));
}

namespace {

// The order in which point i's rays are fed to an encoder: a seeded shuffle (a lattice fed in its
// own order would sweep the sphere and bias a 1/k-step iteration).
void shuffled_rays(const TransferOptions& opt, Eigen::Index i, std::vector<uint32_t>& order) {
  const uint32_t R = static_cast<uint32_t>(opt.rays);
  order.resize(R);
  for (uint32_t k = 0; k < R; ++k) order[k] = k;
  Rng shuffle(opt.seed ^ 0xA24BAED4963EE407ull, point_stream(opt, i) + (uint64_t(opt.first_ray) << 40));
  for (uint32_t k = R; k > 1; --k) std::swap(order[k - 1], order[uint32_t(shuffle.next() % k)]);
}

// A point's variance from its halves' difference d = t_A − t_B (K values; null with a single ray,
// which has nothing to compare with): ‖d‖² n_A n_B / R², and d itself into diff when wanted.
void halves_variance(const double* d, int K, const uint32_t size[2], double* variance, double* diff) {
  if (!d) {
    *variance = INFINITY;
    if (diff) std::fill(diff, diff + K, NAN);
    return;
  }
  double d2 = 0;
  for (int c = 0; c < K; ++c) d2 += d[c] * d[c];
  if (diff) std::copy(d, d + K, diff);
  const double R = double(size[0]) + double(size[1]);
  *variance = d2 * size[0] * size[1] / (R * R);
}

// The encoder per thread, rebuilt when the order or the options change.
struct EncoderSet {
  int order = 0;
  ProgressiveOptions options;
  std::vector<ProgressiveEncoder> encoders;  // the whole set, the even half, the odd half
  std::vector<uint32_t> order_of_rays;
};

bool same_options(const ProgressiveOptions& a, const ProgressiveOptions& b) {
  return a.acceleration == b.acceleration && a.gauss_seidel == b.gauss_seidel && a.non_negative == b.non_negative &&
         a.denominator == b.denominator;
}

// The progressive estimators: the hemisphere's directions in a random order per point (a lattice
// fed in its own order would sweep the sphere and bias a 1/k-step iteration), each followed by
// its mirror below the horizon, where the integrand is 0 and no ray is needed. With a variance
// wanted, the even and odd rays are also encoded apart and compared as the control variate's
// halves are: t = (t_A + t_B)/2 is not how the whole set encodes, but it is the whole set's
// spread that matters, and the halves are each an estimate of half the rays.
void progressive_point_transfer(const RowMatrixX3d& normals, Eigen::Index i, const TransferOptions& opt, const PointRays& buf,
                                double* row, double* variance, double* diff) {
  const int K = sh_count(opt.order);
  const uint32_t R = static_cast<uint32_t>(opt.rays);
  const bool blocked = opt.estimator == TransferEstimator::ProgressiveBlocked;
  thread_local EncoderSet set;
  if (set.order != opt.order || !same_options(set.options, opt.progressive)) {
    std::vector<double> mean_square(size_t(K), 1.0 / (4 * M_PI)), start(static_cast<size_t>(K), 0.0);
    for (int l = 0; l < opt.order; ++l)
      for (int m = -l; m <= l; ++m) start[size_t(sh_index(l, m))] = (2 * l + 1) / (4 * M_PI);  // Σ_m y_lm² = (2l+1)/4π
    set.encoders.assign(3, ProgressiveEncoder(K, 1, opt.progressive, mean_square, start));
    set.order = opt.order, set.options = opt.progressive;
  }
  for (ProgressiveEncoder& e : set.encoders) e.reset();
  const Eigen::Vector3d n = normals.row(i).transpose();
  double unshadowed[kMaxShOrder * kMaxShOrder];
  unshadowed_transfer(opt.order, n, unshadowed);
  uint32_t any_blocked = 0;
  for (uint32_t k = 0; k < R; ++k) any_blocked += occluded(buf.rays[k]);
  const uint32_t size[2] = {(R + 1) / 2, R / 2};
  if (blocked && any_blocked == 0) {  // nothing to encode: the coefficients stay 0 exactly
    std::copy(unshadowed, unshadowed + K, row);
    if (variance) *variance = size[1] ? 0.0 : INFINITY;
    if (diff) std::fill(diff, diff + K, size[1] ? 0.0 : NAN);
    return;
  }
  shuffled_rays(opt, i, set.order_of_rays);
  double y[kMaxShOrder * kMaxShOrder];
  const double zero = 0.0;
  for (uint32_t k : set.order_of_rays) {
    const Eigen::Vector3d& d = buf.directions[k];
    const double c = std::max(0.0, d.dot(n));
    const double value = occluded(buf.rays[k]) == blocked ? c : 0.0;
    sh_eval(opt.order, d.x(), d.y(), d.z(), y);
    set.encoders[0].add(y, &value);
    if (variance) set.encoders[1 + (k & 1)].add(y, &value);
    const Eigen::Vector3d below = d - 2.0 * d.dot(n) * n;
    sh_eval(opt.order, below.x(), below.y(), below.z(), y);
    set.encoders[0].add(y, &zero);
    if (variance) set.encoders[1 + (k & 1)].add(y, &zero);
  }
  const std::vector<double>& b = set.encoders[0].coefficients();
  for (int c = 0; c < K; ++c) row[c] = blocked ? unshadowed[c] - b[size_t(c)] : b[size_t(c)];
  if (!variance) return;
  double d[kMaxShOrder * kMaxShOrder];
  for (int c = 0; c < K; ++c) d[c] = set.encoders[1].coefficients()[size_t(c)] - set.encoders[2].coefficients()[size_t(c)];
  halves_variance(size[1] ? d : nullptr, K, size, variance, diff);
}

// One point's transfer into row (K values), and optionally its estimated variance (summed over
// the K values): the two halves are each an unbiased estimate, t = (n_A t_A + n_B t_B) / R, so
// with per-ray variance σ² the result's is σ²/R = E‖t_A − t_B‖² · n_A n_B / R².
void point_transfer(const RayScene& scene, const RowMatrixX3d& points, const RowMatrixX3d& normals,
                    const RowMatrixX3d* offsets, Eigen::Index i, const TransferOptions& opt, const RaySequence& seq, PointRays& buf,
                    double* row, double* variance, double* diff = nullptr) {
  const int K = sh_count(opt.order);
  double y[kMaxShOrder * kMaxShOrder];
  double acc[kMaxShOrder * kMaxShOrder], acc_a[kMaxShOrder * kMaxShOrder];
  const uint32_t R = static_cast<uint32_t>(opt.rays);
  trace_point(scene, points, normals, offsets, i, opt, seq, buf);
  if (opt.estimator == TransferEstimator::Progressive || opt.estimator == TransferEstimator::ProgressiveBlocked) {
    progressive_point_transfer(normals, i, opt, buf, row, variance, diff);
    return;
  }
  // Visible counts of the even (A) and odd (B) halves.
  uint32_t visible[2] = {0, 0}, size[2] = {(R + 1) / 2, R / 2};
  for (uint32_t k = 0; k < R; ++k) visible[k & 1] += !occluded(buf.rays[k]);
  // β of a half comes from the other half; with a single ray there is no other half. Plain
  // Monte Carlo has none: β = 0, every visible ray counted.
  double beta[2];
  beta[0] = size[1] ? (2 * visible[1] >= size[1] ? 1.0 : 0.0) : 1.0;
  beta[1] = 2 * visible[0] >= size[0] ? 1.0 : 0.0;
  if (opt.estimator == TransferEstimator::MonteCarlo) beta[0] = beta[1] = 0.0;
  std::fill(acc, acc + K, 0.0);
  std::fill(acc_a, acc_a + K, 0.0);
  for (uint32_t k = 0; k < R; ++k) {
    double v = occluded(buf.rays[k]) ? 0.0 : 1.0;
    double w = v - beta[k & 1];
    if (w == 0.0) continue;
    const Eigen::Vector3d& d = buf.directions[k];
    sh_eval(opt.order, d.x(), d.y(), d.z(), y);
    for (int c = 0; c < K; ++c) acc[c] += w * y[c];
    if (variance && (k & 1) == 0)
      for (int c = 0; c < K; ++c) acc_a[c] += w * y[c];
  }
  const double scale = M_PI / R;
  const double beta_mean = (size[0] * beta[0] + size[1] * beta[1]) / R;
  double unshadowed[kMaxShOrder * kMaxShOrder];
  if (beta_mean != 0.0 || (variance && beta[0] != beta[1])) unshadowed_transfer(opt.order, normals.row(i).transpose(), unshadowed);
  for (int c = 0; c < K; ++c) row[c] = (beta_mean != 0.0 ? beta_mean * unshadowed[c] : 0.0) + scale * acc[c];
  if (!variance) return;
  double d[kMaxShOrder * kMaxShOrder];
  for (int c = 0; c < K && size[1]; ++c) {
    const double a = M_PI * acc_a[c] / size[0], b = M_PI * (acc[c] - acc_a[c]) / size[1];
    d[c] = (beta[0] != beta[1] ? (beta[0] - beta[1]) * unshadowed[c] : 0.0) + a - b;
  }
  halves_variance(size[1] ? d : nullptr, K, size, variance, diff);
}

// A replayed call's rows (every point's, gathered over the shards) into a call's outputs.
void replay_rows(const TraceCall& c, Eigen::Index P, int K, double* out, double* variance) {
  if (c.points != uint64_t(P) || c.values_per_point != uint32_t(K) || c.values.size() != size_t(P) * size_t(K) || c.variance.size() != size_t(P))
    throw InputError("the parts were traced for another bake (a call's shape differs)");
  std::copy(c.values.begin(), c.values.end(), out);
  if (variance) std::copy(c.variance.begin(), c.variance.end(), variance);
}

// The record of a slice [first, last) of a call's points; values and variance copied from the
// call's full-size outputs when given.
TraceCall slice_call(uint64_t fingerprint, const TransferOptions& opt, Eigen::Index P, int K, const double* out,
                     const double* variance, uint64_t first, uint64_t last) {
  TraceCall c;
  c.fingerprint = fingerprint;
  c.points = uint64_t(P), c.first = first, c.last = last;
  c.values_per_point = uint32_t(K), c.rays = opt.rays;
  if (out) c.values.assign(out + first * uint64_t(K), out + last * uint64_t(K));
  if (variance) c.variance.assign(variance + first, variance + last);
  return c;
}

void finish_stats(const RayScene& scene, TransferStats* stats, const Stopwatch& clock, Eigen::Index points,
                  int rays) {
  scene.check("tracing transfer rays");
  if (stats) {
    stats->seconds = clock.total();
    stats->rays = static_cast<uint64_t>(points) * static_cast<uint64_t>(rays);
  }
}

}  // namespace

RowMatrixXd shadowed_transfer(const RayScene& scene, const RowMatrixX3d& points,
                              const RowMatrixX3d& normals, const TransferOptions& opt,
                              TransferStats* stats, const ProgressFn& progress, const RowMatrixX3d* offsets,
                              std::vector<double>* variance, RowMatrixXd* half_difference) {
  check_transfer_options(opt);
  const RaySequence seq = ray_sequence(opt);
  const Eigen::Index P = points.rows();
  if (opt.streams && opt.streams->size() != static_cast<size_t>(P)) throw InputError("transfer: one stream per point expected");
  const int K = sh_count(opt.order);
  // With the halves' difference, each row holds the K values and then the K differences: one
  // record for a sharded bake's log, whose fingerprint says which shape it has.
  const int W = half_difference ? 2 * K : K;
  RowMatrixXd out(P, W);  // every row is written, except outside a shard's slice (zeroed there)
  if (variance) variance->assign(static_cast<size_t>(P), 0.0);
  const Stopwatch clock;
  auto finish = [&] {
    if (half_difference) *half_difference = out.rightCols(K), out.conservativeResize(P, K);
  };
  // A sharded bake: the call replayed, or only a slice of its points traced (the rest stay 0).
  Eigen::Index first = 0, last = P;
  TraceLog::Call call;
  const uint64_t fingerprint = opt.log ? trace_fingerprint(points, normals, offsets, nullptr, opt) ^ (half_difference ? 0x4A1FD1FFull : 0) : 0;
  if (opt.log) call = opt.log->begin(fingerprint, uint64_t(P));
  if (call.action == TraceLog::Action::Replay) {
    replay_rows(*call.replay, P, W, out.data(), variance ? variance->data() : nullptr);
    if (progress) progress(static_cast<size_t>(P));
    finish_stats(scene, stats, clock, P, opt.rays);
    finish();
    return out;
  }
  if (call.action == TraceLog::Action::Slice) first = Eigen::Index(call.first), last = Eigen::Index(call.last), out.setZero();
  std::vector<double> own_variance;
  double* var = variance ? variance->data() : nullptr;
  if (!var && (call.action == TraceLog::Action::Slice || half_difference)) own_variance.assign(size_t(P), 0.0), var = own_variance.data();
  parallel_range(last - first, opt.threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& range) {
    thread_local PointRays buf;
    for (Eigen::Index i = first + range.begin(); i != first + range.end(); ++i)
      point_transfer(scene, points, normals, offsets, i, opt, seq, buf, out.row(i).data(), var ? var + i : nullptr,
                     half_difference ? out.row(i).data() + K : nullptr);
    if (progress) progress(static_cast<size_t>(range.size()));
  });
  if (call.action == TraceLog::Action::Slice)
    opt.log->record(slice_call(fingerprint, opt, P, W, out.data(), var, uint64_t(first), uint64_t(last)));
  finish_stats(scene, stats, clock, P, opt.rays);  // the whole call's rays, as one process would count them
  finish();
  return out;
}

RowMatrixXd sg_transfer(const RayScene& scene, const RowMatrixX3d& points, const RowMatrixX3d& normals, const SgBasis& basis,
                        const TransferOptions& options, const RowMatrixX3d* offsets, const ProgressFn& progress) {
  TransferOptions opt = options;
  opt.estimator = TransferEstimator::Progressive;  // the same directions as pls: the hemisphere's lattice
  opt.progressive.non_negative = false;            // checked here, not refused as for SH
  check_transfer_options(opt);
  if (opt.first_ray != 0 || opt.log) throw InputError("spherical-Gaussian transfer: a single round, not sharded");
  if (basis.size() < 1 || !(basis.sharpness > 0)) throw InputError("spherical-Gaussian transfer: an empty lobe set");
  const RaySequence seq = ray_sequence(opt);
  const Eigen::Index P = points.rows();
  const int N = basis.size();
  const Eigen::MatrixXd gram = sg_gram(basis);
  std::vector<double> mean_square(static_cast<size_t>(N), 0.0), start(static_cast<size_t>(N), 1.0);  // unit peaks: the paper's start of 1
  for (int k = 0; k < N; ++k) mean_square[size_t(k)] = gram(k, k) / (4 * M_PI);
  RowMatrixXd out(P, N);
  parallel_range(P, opt.threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& range) {
    thread_local PointRays buf;
    thread_local std::vector<uint32_t> order;
    thread_local std::vector<double> g;
    ProgressiveEncoder encoder(N, 1, options.progressive, mean_square, start);
    g.resize(size_t(N));
    for (Eigen::Index i = range.begin(); i != range.end(); ++i) {
      trace_point(scene, points, normals, offsets, i, opt, seq, buf);
      const Eigen::Vector3d n = normals.row(i).transpose();
      shuffled_rays(opt, i, order);
      encoder.reset();
      const double zero = 0.0;
      for (uint32_t k : order) {
        const Eigen::Vector3d& d = buf.directions[k];
        const double value = occluded(buf.rays[k]) ? 0.0 : std::max(0.0, d.dot(n));
        sg_eval(basis, d, g.data());
        encoder.add(g.data(), &value);
        sg_eval(basis, d - 2.0 * d.dot(n) * n, g.data());  // its mirror below the horizon: 0, no ray
        encoder.add(g.data(), &zero);
      }
      for (int k = 0; k < N; ++k) out(i, k) = encoder.coefficients()[size_t(k)];
    }
    if (progress) progress(static_cast<size_t>(range.size()));
  });
  scene.check("tracing transfer rays");
  return out;
}

void shadowed_transfer_groups(const RayScene& scene, const RowMatrixX3d& points, const RowMatrixX3d& normals,
                              const std::vector<size_t>& group_begin, const TransferOptions& opt, const GroupFn& consume,
                              TransferStats* stats, const ProgressFn& progress, const RowMatrixX3d* offsets) {
  check_transfer_options(opt);
  const RaySequence seq = ray_sequence(opt);
  const Eigen::Index P = points.rows();
  if (opt.streams && opt.streams->size() != static_cast<size_t>(P)) throw InputError("transfer: one stream per point expected");
  if (group_begin.empty() || group_begin.front() != 0 || group_begin.back() != static_cast<size_t>(P) ||
      !std::is_sorted(group_begin.begin(), group_begin.end()))
    throw InputError("transfer: point groups must partition the points in order");
  const auto G = static_cast<Eigen::Index>(group_begin.size() - 1);
  const int K = sh_count(opt.order);
  // About kGrain points per task, whatever the groups' sizes.
  const Eigen::Index grain = std::max<Eigen::Index>(1, G > 0 ? kGrain * G / std::max<Eigen::Index>(P, 1) : 1);
  const Stopwatch clock;
  // A sharded bake: the groups replayed in order, or only a slice of them traced (and kept).
  Eigen::Index g_first = 0, g_last = G;
  TraceLog::Call call;
  const uint64_t fingerprint = opt.log ? trace_fingerprint(points, normals, offsets, &group_begin, opt) : 0;
  if (opt.log) call = opt.log->begin(fingerprint, uint64_t(G));
  if (call.action == TraceLog::Action::Replay) {
    const TraceCall& c = *call.replay;
    if (c.points != uint64_t(P) || c.values_per_point != uint32_t(K) || c.values.size() != size_t(P) * size_t(K))
      throw InputError("the parts were traced for another bake (a call's shape differs)");
    for (Eigen::Index g = 0; g < G; ++g) {
      const size_t first = group_begin[size_t(g)], last = group_begin[size_t(g) + 1];
      consume(size_t(g), c.values.data() + first * size_t(K), c.variance.data() + first, last - first);
    }
    if (progress) progress(static_cast<size_t>(P));
    finish_stats(scene, stats, clock, P, opt.rays);
    return;
  }
  std::vector<double> kept_values, kept_variance;  // a slice's results, by point
  size_t p_first = 0, p_last = size_t(P);
  if (call.action == TraceLog::Action::Slice) {
    g_first = Eigen::Index(call.first), g_last = Eigen::Index(call.last);
    p_first = group_begin[size_t(g_first)], p_last = group_begin[size_t(g_last)];
    kept_values.assign((p_last - p_first) * size_t(K), 0.0), kept_variance.assign(p_last - p_first, 0.0);
  }
  const bool keep = call.action == TraceLog::Action::Slice;
  parallel_range(g_last - g_first, opt.threads, grain, [&](const tbb::blocked_range<Eigen::Index>& range) {
    thread_local PointRays buf;
    thread_local std::vector<double> values, variance;
    size_t done = 0;
    for (Eigen::Index g = g_first + range.begin(); g != g_first + range.end(); ++g) {
      const size_t first = group_begin[size_t(g)], last = group_begin[size_t(g) + 1];
      values.resize((last - first) * size_t(K));
      variance.resize(last - first);
      for (size_t i = first; i < last; ++i)
        point_transfer(scene, points, normals, offsets, static_cast<Eigen::Index>(i), opt, seq, buf, values.data() + (i - first) * size_t(K),
                       variance.data() + (i - first));
      if (keep) {
        std::copy(values.begin(), values.end(), kept_values.begin() + std::ptrdiff_t((first - p_first) * size_t(K)));
        std::copy(variance.begin(), variance.end(), kept_variance.begin() + std::ptrdiff_t(first - p_first));
      }
      consume(size_t(g), values.data(), variance.data(), last - first);
      done += last - first;
    }
    if (progress) progress(done);
  });
  if (keep) {
    TraceCall c = slice_call(fingerprint, opt, P, K, nullptr, nullptr, p_first, p_last);
    c.values = std::move(kept_values), c.variance = std::move(kept_variance);
    opt.log->record(std::move(c));
  }
  finish_stats(scene, stats, clock, P, opt.rays);
}

uint64_t bare_occlusion_loop(const RayScene& scene, const RowMatrixX3d& points,
                             const RowMatrixX3d& normals, const TransferOptions& opt,
                             TransferStats* stats, const RowMatrixX3d* offsets) {
  check_transfer_options(opt);
  const RaySequence seq = ray_sequence(opt);
  if (opt.streams && opt.streams->size() != static_cast<size_t>(points.rows())) throw InputError("transfer: one stream per point expected");
  std::atomic<uint64_t> hits{0};
  const Stopwatch clock;
  parallel_range(points.rows(), opt.threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& range) {
    thread_local PointRays buf;
    uint64_t local = 0;
    for (Eigen::Index i = range.begin(); i != range.end(); ++i) {
      trace_point(scene, points, normals, offsets, i, opt, seq, buf);
      for (const RTCRay& r : buf.rays) local += occluded(r);
    }
    hits += local;
  });
  scene.check("tracing benchmark rays");
  if (stats) {
    stats->seconds = clock.total();
    stats->rays = static_cast<uint64_t>(points.rows()) * static_cast<uint64_t>(opt.rays);
  }
  return hits.load();
}

}  // namespace prtsub

namespace prtsub {

RowMatrixX3d offset_directions(const std::vector<uint32_t>& position_of, const RowMatrixX3d& normals) {
  std::unordered_map<uint32_t, Eigen::Vector3d> sum;
  for (size_t v = 0; v < position_of.size(); ++v) {
    auto [it, inserted] = sum.emplace(position_of[v], Eigen::Vector3d::Zero());
    it->second += normals.row(static_cast<Eigen::Index>(v)).transpose();
  }
  RowMatrixX3d out(normals.rows(), 3);
  for (size_t v = 0; v < position_of.size(); ++v) {
    const Eigen::Vector3d own = normals.row(static_cast<Eigen::Index>(v)).transpose();
    const Eigen::Vector3d& s = sum[position_of[v]];
    const double len = s.norm();
    // Mean direction, unless the sides nearly cancel or it leans away from this side.
    Eigen::Vector3d d = len > 1e-6 ? Eigen::Vector3d(s / len) : own;
    if (d.dot(own) < 0.05) d = own;
    out.row(static_cast<Eigen::Index>(v)) = d.transpose();
  }
  return out;
}

RowMatrixX3d vertex_offset_directions(const Mesh& mesh) { return offset_directions(mesh.vertex_position, mesh.normals); }

}  // namespace prtsub
