// The bake pipeline. Data flows one way, each stage a call into its own room:
//
//   uniform refinement (subdiv/uniform)  →  one Embree scene of the (unchanged) geometry
//   →  transfer at every render vertex (transfer)  →  adaptive refinement, asking the scene for
//   new vertices' transfer (subdiv/refine through refine_signal)  →  surface samples and their
//   transfer, reduced to face moments as they are traced  →  the fit (fit)  →  AO clamping.
//
// Linear uniform and adaptive refinement keep the geometry, so one scene serves throughout;
// Loop moves it, and the scene is built after it. Seeds: the vertices' rays depend on
// (transfer.seed, render-vertex index), the samples' on a seed derived from transfer.seed, so
// a bake is a function of its options and the mesh, not of threads or batching.
//
// Spherical-Gaussian bakes (sg_lobes) take a short branch of the same flow: each vertex's lobes
// from the progressive encoder, then adaptive refinement on their whitened rows (bake_lobes);
// the stages after it are SH's.
#include "prtsub/prt/bake.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <cstdio>

#include "prtsub/prt/closest_point.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/sg_basis.h"
#include "prtsub/prt/sh.h"
#include "prtsub/prt/trace_log.h"
#include "prtsub/prt/vertex_top_up.h"
#include "prtsub/subdiv/adjacency.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/stopwatch.h"
#include "prtsub/version.h"

namespace prtsub {

Refinement parse_refinement(const std::string& name) {
  if (name == "none") return Refinement::None;
  if (name == "adaptive") return Refinement::Adaptive;
  if (name == "uniform") return Refinement::Uniform;
  if (name == "auto") return Refinement::Auto;
  throw InputError("unknown refinement '" + name + "' (none, adaptive, uniform, auto)");
}

const char* refinement_name(Refinement r) {
  switch (r) {
    case Refinement::None: return "none";
    case Refinement::Adaptive: return "adaptive";
    case Refinement::Uniform: return "uniform";
    case Refinement::Auto: return "auto";
  }
  return "?";
}

bool early_stop_on(const BakeOptions& o) { return o.round_rays > 0 && o.transfer.rays > o.round_rays; }

namespace {

// What a spherical-Gaussian bake takes: the vertices' own lobes (BakeOptions::sg_lobes).
void check_lobe_options(const BakeOptions& o) {
  const std::string sg = "--basis sg:" + std::to_string(o.sg_lobes) + ": ";
  if (o.sg_lobes < kMinSgLobes || o.sg_lobes > kMaxSgAssetLobes)
    throw InputError("spherical Gaussians: an asset takes " + std::to_string(kMinSgLobes) + " to " + std::to_string(kMaxSgAssetLobes) +
                     " lobes, got " + std::to_string(o.sg_lobes));
  const char* refused = o.signal != AssetSignal::Transfer          ? "lobes are transfer, not ambient occlusion"
                        : o.fit.method != FitMethod::Point         ? "the vertices' own lobes only (--fit point); the fit is SH's"
                        : o.bounce.bounces > 0                     ? "interreflection is SH's"
                        : o.albedo_colour.coloured()               ? "a coloured albedo is SH's (it only matters with bounces)"
                        : o.target_error > 0                       ? "--error is SH's (its hold-out is measured in SH)"
                        : o.order_auto                             ? "--order auto chooses an SH order"
                        : early_stop_on(o)                         ? "early stop is SH's (use --rays-fixed)"
                        : o.transfer.log != nullptr                ? "a sharded bake is SH's"
                        : o.refine == Refinement::Auto             ? "--refine auto is SH's (its simplification ranks collapses in SH)"
                        : o.transfer.first_ray != 0                ? "a single round of rays"
                        : o.refine_only                            ? "--stage refine is for sharded bakes, which are SH's"
                                                                   : nullptr;
  if (refused) throw InputError(sg + refused);
}

}  // namespace

void check_bake_options(const BakeOptions& o) {
  check_transfer_options(o.transfer);
  if (o.round_rays != 0 && (o.round_rays < 2 || o.round_rays % 2 != 0 || o.round_rays > (1 << 20)))
    throw InputError("an early stop's first round must be an even count of rays from 2, got " + std::to_string(o.round_rays));
  if (!(o.stop_noise_percent >= 0) || !std::isfinite(o.stop_noise_percent))
    throw InputError("an early stop's noise must be a finite, non-negative percentage, got " + std::to_string(o.stop_noise_percent));
  if (o.bounce.bounces < 0 || o.bounce.bounces > 64) throw InputError("bounces must be between 0 and 64, got " + std::to_string(o.bounce.bounces));
  if (!(o.bounce.albedo >= 0 && o.bounce.albedo <= 1)) throw InputError("albedo must be between 0 and 1, got " + std::to_string(o.bounce.albedo));
  if (o.bounce.bounces > 0 && o.signal == AssetSignal::Ao)
    throw InputError("interreflection is for transfer assets: ambient occlusion is visibility, not light");
  if (o.albedo_colour.coloured() && o.signal == AssetSignal::Ao)
    throw InputError("a coloured albedo is for transfer assets: ambient occlusion is visibility, not light");
  if (o.albedo_colour.source == AlbedoSource::Constant &&
      !(o.albedo_colour.constant.minCoeff() >= 0 && o.albedo_colour.constant.maxCoeff() <= 1))
    throw InputError("albedo must be between 0 and 1 in every channel");
  if (o.order_auto && o.signal == AssetSignal::Ao) throw InputError("--order auto is for transfer assets: ambient occlusion has one coefficient");
  if (o.sample_rays < 1 || o.sample_rays > (1 << 20))
    throw InputError("rays per sample must be between 1 and 1048576, got " + std::to_string(o.sample_rays));
  if ((o.refine == Refinement::Adaptive || o.refine == Refinement::Auto) && o.adaptive.budget == 0)
    throw InputError(std::string(refinement_name(o.refine)) + " refinement needs a triangle budget");
  if (!(o.auto_share > 0 && o.auto_share <= 1)) throw InputError("auto refinement: the share to simplify to must be in (0, 1], got " + std::to_string(o.auto_share));
  if (o.auto_cycles < 0 || o.auto_cycles > 8) throw InputError("auto refinement: further cycles must be 0 to 8, got " + std::to_string(o.auto_cycles));
  if (!(o.auto_cycle_share > 0 && o.auto_cycle_share <= 0.5))
    throw InputError("auto refinement: the share a cycle collapses must be in (0, 0.5], got " + std::to_string(o.auto_cycle_share));
  if (o.refine == Refinement::Uniform && (o.uniform.levels < 1 || o.uniform.levels > 8))
    throw InputError("uniform refinement: levels must be between 1 and 8, got " + std::to_string(o.uniform.levels));
  if (!(o.target_error >= 0) || !std::isfinite(o.target_error))
    throw InputError("--error must be a finite, non-negative percentage, got " + std::to_string(o.target_error));
  if (!(o.fit.alpha >= 0) || !std::isfinite(o.fit.alpha))
    throw InputError("fit: alpha must be finite and non-negative, got " + std::to_string(o.fit.alpha));
  if (!(o.simplified_alpha >= 0) || !std::isfinite(o.simplified_alpha))
    throw InputError("fit: the simplified mesh's alpha must be finite and non-negative, got " + std::to_string(o.simplified_alpha));
  if (o.sg_lobes != 0) check_lobe_options(o);
}

void check_fixed_mesh(const BakeOptions& o) {
  if (o.refine == Refinement::Adaptive || o.refine == Refinement::Auto)
    throw InputError("a sharded bake needs a fixed mesh: write the adaptive mesh first (bake --stage refine), then shard its bake");
}

namespace {

// The variance of a chunk's three moment rows Σ_k w_k h_c(p_k) f_k, each summed over its K
// values: the samples' rays are independent, so it is Σ_k (w_k h_c(p_k))² var f_k, with each
// sample's variance from its own two ray halves. Positional error is left out: the samples are a
// shifted lattice, whose stratification makes it small next to the rays' (and the difference of
// a lattice's halves, its usual estimate, mistakes a shadow edge inside a face for noise).
void chunk_variance(const SurfaceSamples& s, size_t first, size_t last, const double* variance, double* out) {
  out[0] = out[1] = out[2] = 0;
  for (size_t k = first; k < last; ++k, ++variance)
    for (int c = 0; c < 3; ++c) {
      const double wh = s.weight[k] * s.barycentric(static_cast<Eigen::Index>(k), c);
      out[c] += wh * wh * *variance;
    }
}

}  // namespace

FaceMoments trace_face_moments(const Mesh& mesh, const RayScene& scene, const SurfaceSamples& samples,
                               const TransferOptions& options, TransferStats* stats, const ProgressFn& progress) {
  // Samples are traced in chunks of at most kChunk, each reduced to its three moment rows as
  // soon as it is traced: storing every sample's transfer would cost a row per sample and the
  // time to write it. A face's chunks are then summed in order, so the result does not depend
  // on the threads; chunks rather than faces, because one face may hold most of the samples
  // (a floor) and one thread traces a chunk. Chunks are disjoint, so their variances add up.
  constexpr size_t kChunk = 64;
  const size_t F = mesh.num_faces();
  std::vector<size_t> chunk_begin{0}, first_chunk(F + 1, 0);
  for (size_t f = 0; f < F; ++f) {
    first_chunk[f] = chunk_begin.size() - 1;
    for (size_t k = samples.begin[f]; k < samples.begin[f + 1]; k += kChunk) chunk_begin.push_back(std::min(k + kChunk, samples.begin[f + 1]));
  }
  first_chunk[F] = chunk_begin.size() - 1;
  const Eigen::Index K = sh_count(options.order);
  const size_t chunks = chunk_begin.size() - 1;
  RowMatrixXd partial(static_cast<Eigen::Index>(3 * chunks), K);
  std::vector<double> partial_variance(3 * chunks, 0.0);
  shadowed_transfer_groups(
      scene, samples.points, samples.normals, chunk_begin, options,
      [&](size_t c, const double* values, const double* variance, size_t) {
        sample_moments(samples, chunk_begin[c], chunk_begin[c + 1], values, K, partial.row(static_cast<Eigen::Index>(3 * c)).data());
        chunk_variance(samples, chunk_begin[c], chunk_begin[c + 1], variance, partial_variance.data() + 3 * c);
      },
      stats, progress, &samples.offsets);
  FaceMoments m{RowMatrixXd::Zero(static_cast<Eigen::Index>(3 * F), K), std::vector<double>(3 * F, 0.0)};
  for (size_t f = 0; f < F; ++f)
    for (size_t c = first_chunk[f]; c < first_chunk[f + 1]; ++c) {
      m.rows.middleRows(static_cast<Eigen::Index>(3 * f), 3) += partial.middleRows(static_cast<Eigen::Index>(3 * c), 3);
      for (int k = 0; k < 3; ++k) m.variance[3 * f + size_t(k)] += partial_variance[3 * c + size_t(k)];
    }
  return m;
}

BakeOptions resolve_bake_options(const BakeOptions& in) {
  BakeOptions o = in;
  if (o.signal == AssetSignal::Ao) o.transfer.order = 1;
  o.samples.seed = mix64(o.transfer.seed + 17);
  o.fit.threads = o.transfer.threads;
  o.bounce.rays = o.transfer.rays, o.bounce.seed = o.transfer.seed, o.bounce.threads = o.transfer.threads;
  const bool unshadowed = o.unshadowed_projection && o.signal == AssetSignal::Transfer && o.fit.method == FitMethod::LeastSquares;
  o.fit.unshadowed_order = unshadowed ? o.transfer.order : 0;
  o.pilot.exact_unshadowed = unshadowed;
  if (o.sample_rays_auto) o.pilot.sample_ray_choices.assign(o.sample_ray_choices.begin(), o.sample_ray_choices.end());
  else o.pilot.sample_ray_choices.clear();
  return o;
}

namespace {

// The vertices' first round: what later rounds at a vertex continue.
TransferOptions first_round(const BakeOptions& o) {
  TransferOptions t = o.transfer;
  if (early_stop_on(o)) t.rays = o.round_rays;
  return t;
}

std::string estimator_description(const TransferOptions& t) {
  if (t.estimator == TransferEstimator::ControlVariate) return "cosine-lattice cross-fitted-control-variate";
  if (t.estimator == TransferEstimator::MonteCarlo) return "plain Monte Carlo projection, independent cosine-weighted directions";
  char buf[200];
  const ProgressiveOptions& p = t.progressive;
  std::snprintf(buf, sizeof buf, "progressive least-squares (Roughton 2020)%s, %s, acceleration %g, %s denominator",
                t.estimator == TransferEstimator::ProgressiveBlocked ? " of the blocked part" : "", p.gauss_seidel ? "Gauss-Seidel" : "Jacobi",
                p.acceleration,
                p.denominator == ProgressiveOptions::Denominator::Interpolated ? "interpolated"
                : p.denominator == ProgressiveOptions::Denominator::Clamped    ? "clamped"
                                                                               : "running");
  return buf;
}

Metadata bake_metadata(const BakeOptions& o, const BakeResult& r) {
  Metadata m = o.signal == AssetSignal::Ao ? ao_metadata()
               : o.sg_lobes > 0            ? sg_convention_metadata(sg_basis(o.sg_lobes), !o.sg_signed)
                                           : sh_convention_metadata(o.transfer.order);
  m.push_back({"source", o.source.empty() ? "(in memory)" : o.source});
  m.push_back({"rays", std::to_string(o.transfer.rays)});
  if (early_stop_on(o)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "each vertex from %d rays, doubling to at most %d until its noise is at most %g%% of ||t_unshadowed||",
                  o.round_rays, o.transfer.rays, o.stop_noise_percent);
    m.push_back({"early_stop", buf});
  }
  m.push_back({"seed", std::to_string(o.transfer.seed)});
  m.push_back({"threads", std::to_string(o.transfer.threads) + " (results do not depend on it)"});
  m.push_back({"crease_angle", std::to_string(r.mesh.crease_angle_deg)});
  m.push_back({"normals", r.mesh.normals_from_file ? "file" : "computed"});
  TransferOptions estimator = o.transfer;
  if (o.sg_lobes > 0) estimator.estimator = TransferEstimator::Progressive;  // sg_transfer's, whatever --estimator says
  m.push_back({"estimator", estimator_description(estimator)});
  if (o.order_auto && r.order.order > 0) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%d (what it leaves out, %.3f%% of ||t_unshadowed||, %s %.3f%%%s; pilot of %zu vertices to order %d)",
                  r.order.order, r.order.truncation_percent[static_cast<size_t>(r.order.order - 1)], r.order.reached ? "is within" : "exceeds",
                  r.order.tolerance_percent, o.order_choice.tolerance_percent > 0 ? ", the tolerance" : ", the bake's own noise at that order",
                  r.order.points, o.order_choice.max_order);
    m.push_back({"order_auto", buf});
  }
  m.push_back({"refine", refinement_name(o.refine)});
  if (o.refine == Refinement::Auto)
    m.push_back({"auto", "simplified to " + std::to_string(r.simplify.faces_after) + " triangles (share " + std::to_string(o.auto_share) +
                             "), then refined to " + std::to_string(r.mesh.num_faces()) + "; new vertices traced at their closest input points; " +
                             std::to_string(r.auto_cycles) + " further cycle(s) (share " + std::to_string(o.auto_cycle_share) +
                             ") collapsed " + std::to_string(r.auto_cycle_collapses) + " times and refined back"});
  if (o.refine == Refinement::Adaptive || o.refine == Refinement::Auto) {
    m.push_back({"budget", std::to_string(o.adaptive.budget)});
    m.push_back({"estimate", estimate_name(o.estimate)});
    m.push_back({"max_edge", std::to_string(o.adaptive.max_edge)});
    m.push_back({"batch", std::to_string(o.adaptive.batch)});
    if (r.simplified) {
      char buf[240];
      std::snprintf(buf, sizeof buf, "%zu -> %zu triangles, metric %s, min angle %g, geometry weight %g, feature tolerance %g",
                    r.simplify.faces_before, r.simplify.faces_after, simplify_metric_name(o.simplify.metric), o.simplify.min_angle_deg,
                    o.simplify.geometry_weight, o.simplify.feature_tolerance);
      m.push_back({"simplified", buf});
      m.push_back({"source_face", "the input face each output face was before collapses reshaped it; eval locates points by closest point"});
    }
  }
  if (o.refine == Refinement::Uniform) {
    m.push_back({"levels", std::to_string(o.uniform.levels)});
    m.push_back({"scheme", uniform_scheme_name(o.uniform.scheme)});
  }
  if (o.refine_only) m.push_back({"stage", "refine (the refined mesh and its point values, to bake again)"});
  m.push_back({"fit", o.refine_only ? "point" : fit_method_name(o.fit.method)});
  if (o.fit.method != FitMethod::Point && !o.refine_only) {
    m.push_back({"samples", std::to_string(r.fit_data.samples.size())});
    m.push_back({"sample_allocation", sample_allocation_name(r.fit_data.allocation)});
    const bool pilot = r.fit_data.allocation == SampleAllocation::Pilot;
    if (pilot || r.fit_data.plan.holdout.size() > 0) {  // a simplified asset's hold-out lies on the input's surface
      char buf[128];
      std::snprintf(buf, sizeof buf, "%.3f%% +- %.3f%% (eval's unit, on %zu %s)", r.predicted.percent, r.predicted.standard_error,
                    r.predicted.samples, pilot ? "held-out pilot samples" : "samples held out of the input's surface");
      m.push_back({"predicted_error", buf});
    }
    if (pilot) {
      if (o.target_error > 0)
        m.push_back({"target_error", std::to_string(o.target_error) + "% (" + std::to_string(r.target_rays) + " more vertex rays in " +
                                         std::to_string(r.target_rounds) + " rounds, " + std::to_string(r.target_samples) +
                                         " more samples in " + std::to_string(r.target_sample_rounds) + ")"});
      m.push_back({"pilot_samples", std::to_string(r.fit_data.plan.pilot_samples) + " (" + std::to_string(o.pilot.rays) + " rays each)"});
      m.push_back({"sampled_faces", std::to_string(r.fit_data.plan.sampled_faces)});
      m.push_back({"extra_vertex_rays", std::to_string(r.top_up.rays) + " at " + std::to_string(r.top_up.vertices) + " vertices"});
    }
    m.push_back({"sample_rays", std::to_string(r.fit_data.sample_rays > 0 ? r.fit_data.sample_rays : o.sample_rays)});
  }
  if (o.fit.method == FitMethod::LeastSquares && !o.refine_only) {
    std::string alpha = std::to_string(r.simplified && r.simplify.collapses > 0 && (o.refine != Refinement::Auto || r.refine.splits == 0)
                                           ? o.simplified_alpha : o.fit.alpha);
    if (!r.alpha_trials.empty()) {
      alpha += " (auto: the lowest held-out error of";
      char buf[64];
      for (const auto& [a, e] : r.alpha_trials) std::snprintf(buf, sizeof buf, " %g: %.3f%%", a, e), alpha += buf;
      alpha += ")";
    }
    m.push_back({"alpha", alpha});
    m.push_back({"regularizer", regularizer_name(o.fit.regularizer)});
    m.push_back({"mass", mass_matrix_name(o.fit.mass)});
    m.push_back({"noise_weighting", o.fit.weigh_by_noise ? "on" : "off"});
    if (o.fit.unshadowed_order > 0 && !(r.simplified && r.simplify.collapses > 0))
      m.push_back({"unshadowed", "projected: the curvature of t_u(n) (the clamped cosine at the interpolated normal) inside the faces, "
                                 "scaled by each vertex's open share, is fitted in closed form"});
    m.push_back({"non_negative", non_negative_name(o.fit.non_negative)});
  }
  const bool coloured = o.albedo_colour.coloured();
  if (coloured) m.push_back({"albedo", albedo_description(o.albedo_colour)});
  if (r.rekeyed_at > 0)
    m.push_back({"bounce_rekey", std::to_string(r.rekeyed_at) + " (refined on direct light to this many triangles, then keyed on direct plus bounced light)"});
  if (r.bounce.passes > 0) {
    char buf[160];
    char grey[32];
    std::snprintf(grey, sizeof grey, "%.4g", o.bounce.albedo);
    const std::string albedo = coloured ? std::string("coloured") : std::string(grey);
    std::snprintf(buf, sizeof buf, "%d (albedo %s; the last pass added %.4f%% of ||t_unshadowed||%s)", r.bounce.passes, albedo.c_str(),
                  r.bounce.change_percent.back(), o.bounce.until_converged ? ", auto: below the bake's noise" : "");
    m.push_back({"bounces", buf});
    m.push_back({"interreflection", "t_i holds the bounces: each adds (albedo/pi)*integral((1-V)*t_i(hit)*max(n.w,0)); back faces black; radiance=albedo/pi*sum(l_i*t_i)"});
    if (coloured)
      m.push_back({"channels", "rgb r_t*, g_t*, b_t*: each channel's transfer bounced by that channel's albedo; the receiver's own albedo "
                               "(albedo_r/g/b) is not in it: radiance_c=albedo_c/pi*sum(l_c,i*t_c,i)"});
  }
  m.push_back({"generator", std::string("prtsub ") + kVersion});
  return m;
}

void refine_adaptively(const RayScene& scene, const BakeOptions& o, BakeResult& r, const Mesh* project_onto = nullptr) {
  TransferSignalOptions so;
  so.estimate = o.estimate;
  so.transfer = o.transfer;
  so.project_onto = project_onto;
  TransferSignal signal(scene, so);
  const size_t before = r.mesh.num_vertices();
  r.refine = refine_adaptive(r.mesh, r.transfer, signal, o.adaptive);
  r.rays += signal.rays();
  r.point_variance.resize(r.mesh.num_vertices(), 0.0);
  r.vertex_rays.resize(r.mesh.num_vertices(), 0.0);
  for (size_t i = before; i < r.mesh.num_vertices() && i < signal.variance().size(); ++i)
    r.point_variance[i] = signal.variance()[i], r.vertex_rays[i] = o.transfer.rays;
  if (!r.refine.warning.empty()) r.warnings.push_back(r.refine.warning);
}

// Spherical-Gaussian lobes (BakeOptions::sg_lobes): each vertex's own encoding, then adaptive
// refinement keyed on the lobes' L² distance. Refinement compares rows by Euclidean distance; the
// lobes overlap, so the rows are whitened by the Cholesky factor of their Gram matrix for it
// (c L, G = L Lᵀ: ‖Δc L‖² = Δcᵀ G Δc = ∫ (ΔT)²) and turned back after. SH rows need no such step:
// the SH are orthonormal.
void bake_lobes(const RayScene& scene, const RowMatrixX3d& offsets, const BakeOptions& o, const BakeProgress& progress, Stopwatch& clock,
                BakeResult& r) {
  const SgBasis basis = sg_basis(o.sg_lobes);
  TransferOptions t = o.transfer;
  t.progressive.non_negative = !o.sg_signed;
  const size_t V = r.mesh.num_vertices();
  if (progress.stage) progress.stage("transfer", V);
  r.transfer = sg_transfer(scene, vertex_positions(r.mesh), r.mesh.normals, basis, t, &offsets, progress.add);
  r.rays += uint64_t(V) * uint64_t(t.rays);
  r.vertex_rays.assign(V, t.rays);
  r.point_variance.assign(V, NAN);  // one encoding per vertex: no halves to tell its noise
  r.seconds_transfer = clock.lap();
  if (o.refine == Refinement::Adaptive) {
    if (o.adaptive.budget < r.mesh.num_faces())
      throw InputError("--basis sg:" + std::to_string(o.sg_lobes) + ": a budget below the input's " + std::to_string(r.mesh.num_faces()) +
                       " triangles simplifies, and simplification ranks collapses in SH");
    const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(sg_gram(basis)).matrixL();
    TransferSignalOptions so;
    so.estimate = o.estimate, so.transfer = t, so.lobes = &basis, so.lobe_metric = L;
    TransferSignal signal(scene, so);
    RowMatrixXd whitened = r.transfer * L;
    r.refine = refine_adaptive(r.mesh, whitened, signal, o.adaptive);
    r.transfer = L.transpose().triangularView<Eigen::Upper>().solve(whitened.transpose()).transpose();
    if (!o.sg_signed) r.transfer = r.transfer.cwiseMax(0.0);  // the round trip's last bits
    r.rays += signal.rays();
    r.vertex_rays.resize(r.mesh.num_vertices(), t.rays);
    r.point_variance.resize(r.mesh.num_vertices(), NAN);
    if (!r.refine.warning.empty()) r.warnings.push_back(r.refine.warning);
    r.seconds_refine = clock.lap();
  }
  r.point = r.transfer;
  r.point_halves = RowMatrixXd::Constant(Eigen::Index(r.mesh.num_vertices()), r.transfer.cols(), NAN);
}

// Refinement keyed on bounced light: each new vertex is traced for its direct transfer (the
// signal underneath), and takes its edge's midpoint of the light the bounces added, so the queue
// sees direct plus bounced transfer. The direct part is kept for the passes that follow.
class BouncedSignal : public RefinementSignal {
 public:
  BouncedSignal(TransferSignal& direct_signal, RowMatrixXd direct, RowMatrixXd bounced)
      : inner_(direct_signal), direct_(std::move(direct)), bounced_(std::move(bounced)) {}
  void probe_faces(const std::vector<FaceProbe>& faces, std::vector<double>& extra) override { inner_.probe_faces(faces, extra); }
  double edge_error(const EdgeView& edge) const override { return inner_.edge_error(edge); }
  void compute_values(const std::vector<NewVertex>& batch, const RowMatrixXd& parent_values, RowMatrixXd& values) override {
    inner_.compute_values(batch, parent_values, values);
    if (batch.empty()) return;
    const auto end = static_cast<Eigen::Index>(batch.back().index) + 1;
    if (direct_.rows() < end) direct_.conservativeResize(end, Eigen::NoChange), bounced_.conservativeResize(end, Eigen::NoChange);
    for (size_t i = 0; i < batch.size(); ++i) {
      const auto v = static_cast<Eigen::Index>(batch[i].index), row = static_cast<Eigen::Index>(i);
      direct_.row(v) = values.row(row);
      bounced_.row(v) = 0.5 * (bounced_.row(batch[i].a) + bounced_.row(batch[i].b));
      values.row(row) += bounced_.row(v);
    }
  }
  const RowMatrixXd& direct() const { return direct_; }

 private:
  TransferSignal& inner_;
  RowMatrixXd direct_, bounced_;  // per render vertex: traced direct transfer, and the bounces' light
};

// The scene a bounce needs: one holding r.mesh's own triangles in order (see the bounce stage).
std::unique_ptr<RayScene> scene_for(const Mesh& mesh, const RayScene& scene, const BakeOptions& o) {
  if (o.refine != Refinement::Adaptive && o.refine != Refinement::Auto) return nullptr;  // none or uniform: the scene is the mesh's
  (void)scene;
  return std::make_unique<RayScene>(mesh.positions, position_triangles(mesh));
}

// A later refinement pass's counts added to the first's; the angles are the last pass's.
void add_refinement(RefineStats& into, const RefineStats& more) {
  into.splits += more.splits, into.boundary_splits += more.boundary_splits, into.new_vertices += more.new_vertices;
  into.batches += more.batches, into.faces_popped += more.faces_popped, into.probed_faces += more.probed_faces;
  into.walk_steps += more.walk_steps, into.non_manifold_splits += more.non_manifold_splits;
  into.min_angle_after_deg = more.min_angle_after_deg, into.faces_below_1deg_after = more.faces_below_1deg_after;
  into.seconds_signal += more.seconds_signal, into.seconds_total += more.seconds_total;
}

void refine_rekeyed(const RayScene& scene, const BakeOptions& o, const BakeProgress& progress, BakeResult& r) {
  BakeOptions first = o;
  first.adaptive.budget = static_cast<size_t>(o.rekey_share * double(o.adaptive.budget));
  refine_adaptively(scene, first, r);
  r.rekeyed_at = r.mesh.num_faces();
  if (progress.stage) progress.stage("bounces to key on", 0);
  BounceOptions b = o.bounce;
  b.until_converged = false, b.bounces = std::min(o.bounce.bounces, 16), b.colour = nullptr;
  if (o.albedo_colour.coloured()) b.albedo = o.albedo_colour.constant.mean();  // a grey key (a map's or colours': their first use below)
  BounceStats st;
  const RayScene keyed_scene(r.mesh.positions, position_triangles(r.mesh));  // the bounces read its triangles
  const RowMatrixXd total = interreflected_transfer(r.mesh, keyed_scene, r.transfer, b, &st);
  r.rays += st.rays;
  TransferSignalOptions so;
  so.estimate = o.estimate;
  so.transfer = o.transfer;
  TransferSignal inner(scene, so);
  BouncedSignal signal(inner, r.transfer, total - r.transfer);
  RowMatrixXd values = total;
  const size_t before = r.mesh.num_vertices();
  const RefineStats second = refine_adaptive(r.mesh, values, signal, o.adaptive);
  r.rays += inner.rays();
  r.transfer = signal.direct().topRows(static_cast<Eigen::Index>(r.mesh.num_vertices()));
  r.point_variance.resize(r.mesh.num_vertices(), 0.0);
  r.vertex_rays.resize(r.mesh.num_vertices(), 0.0);
  for (size_t i = before; i < r.mesh.num_vertices() && i < inner.variance().size(); ++i)
    r.point_variance[i] = inner.variance()[i], r.vertex_rays[i] = o.transfer.rays;
  add_refinement(r.refine, second);
  if (!second.warning.empty()) r.warnings.push_back(second.warning);
}

// A budget below the input's: collapse where the transfer does not change. Surviving vertices
// keep their traced transfer and its variance; the render vertices a crease corner's collapse
// moved onto a neighbour's position (an input vertex, so on the source surface) are traced again
// there, with their own normals.
void simplify_adaptively(const RayScene& scene, const BakeOptions& o, BakeResult& r, const ProgressFn& progress,
                         std::vector<uint32_t>* removed_to = nullptr, const Mesh* project_onto = nullptr) {
  SimplifyOptions so = o.simplify;
  so.budget = o.adaptive.budget;
  so.value_scale = unshadowed_norm(o.transfer.order);
  std::vector<uint32_t> to;
  r.simplified = true;
  // Ranked net of the traced values' noise, smoothed as the second round's plan is (one lattice
  // pair's estimate is itself noisy): sibenik at half 4.708% to 4.644%, mori_knob at a tenth
  // 4.335% to 4.192% (docs/simplification.md).
  const std::vector<double> noise = smoothed_variance(r.mesh, r.point_variance, r.vertex_rays);
  r.simplify = simplify(r.mesh, r.transfer, so, &to, progress, &noise);
  std::vector<double> variance(r.mesh.num_vertices(), 0.0), rays(r.mesh.num_vertices(), 0.0);
  for (size_t i = 0; i < to.size() && i < r.point_variance.size(); ++i)
    if (to[i] != UINT32_MAX) variance[to[i]] = r.point_variance[i], rays[to[i]] = r.vertex_rays[i];
  r.point_variance = std::move(variance);
  r.vertex_rays = std::move(rays);
  if (!r.simplify.moved.empty() && r.transfer.cols() > 0) {
    const std::vector<uint32_t>& moved = r.simplify.moved;
    const RowMatrixX3d offsets = vertex_offset_directions(r.mesh);
    RowMatrixX3d points(Eigen::Index(moved.size()), 3), normals(Eigen::Index(moved.size()), 3), off(Eigen::Index(moved.size()), 3);
    for (size_t i = 0; i < moved.size(); ++i) {
      points.row(Eigen::Index(i)) = r.mesh.positions.row(r.mesh.vertex_position[moved[i]]);
      normals.row(Eigen::Index(i)) = r.mesh.normals.row(moved[i]);
      off.row(Eigen::Index(i)) = offsets.row(moved[i]);
    }
    // After refinement (both ways' further cycles) a neighbour may be one of its vertices, which
    // lie near the input's surface, not on it: traced at the closest point on the input instead,
    // as refinement traced that neighbour, not inside the input's geometry.
    if (project_onto) project_onto_surface(*project_onto, vertex_offset_directions(*project_onto), points, normals, &off, o.transfer.threads);
    TransferStats st;
    std::vector<double> v;
    const TransferOptions t = first_round(o);
    const RowMatrixXd traced = shadowed_transfer(scene, points, normals, t, &st, {}, &off, &v);
    for (size_t i = 0; i < moved.size(); ++i) {
      r.transfer.row(moved[i]) = traced.row(Eigen::Index(i));
      r.point_variance[moved[i]] = v[i], r.vertex_rays[moved[i]] = t.rays;
    }
    r.rays += st.rays;
  }
  if (!r.simplify.warning.empty()) r.warnings.push_back(r.simplify.warning);
  if (removed_to) *removed_to = std::move(to);
}

// --refine auto: collapse where the transfer is smooth, then split where it varies. Simplified
// first to a share of the smaller of the budget and the input's count (a share the simplifier
// cannot reach, its locked corners and surface tolerance permitting, is no failure here: it
// stops where it must), then refined to exactly the budget. The simplified surface lies within
// its tolerance of the input, not on it, so refinement's new vertices are traced at their
// closest points on the input (TransferSignalOptions::project_onto); the fit then samples the
// input's surface (fit_to_source), as for any simplified mesh, after a second round of rays at
// the input's own vertices and with α chosen on a hold-out drawn there, as the default bake's.
void refine_both_ways(const Mesh& source, const RayScene& scene, const BakeOptions& o, const BakeProgress& progress, BakeResult& r) {
  const size_t T = o.adaptive.budget, F = r.mesh.num_faces();
  BakeOptions down = o;
  down.adaptive.budget = std::max<size_t>(2, static_cast<size_t>(o.auto_share * double(std::min(T, F))));
  // The share is a target, not a promise: the surface tolerance is not relaxed to reach it (a
  // surface moved further costs more error than the triangles it frees save: sibenik, 3.51%
  // at 0.5 of the input against 4.07% when relaxed to reach 0.35).
  down.simplify.max_surface_tolerance = down.simplify.surface_tolerance;
  if (progress.stage) progress.stage("simplify", 0);
  if (down.adaptive.budget < F) {
    simplify_adaptively(scene, down, r, progress.add);
    if (!r.simplify.warning.empty()) r.warnings.pop_back();  // the share is a target, not a promise
  }
  if (r.mesh.num_faces() > T) {  // it could not go below the budget on the way down: the budget is the promise
    const SimplifyStats first = r.simplify;
    const bool ran = r.simplified;
    down.adaptive.budget = T;
    down.simplify.max_surface_tolerance = o.simplify.max_surface_tolerance;
    simplify_adaptively(scene, down, r, progress.add);
    if (ran) r.simplify.collapses += first.collapses, r.simplify.faces_before = first.faces_before, r.simplify.seconds += first.seconds;
  }
  const size_t before = r.mesh.num_vertices();
  if (r.mesh.num_faces() < T) refine_adaptively(scene, o, r, r.simplified && r.simplify.collapses > 0 ? &source : nullptr);
  r.refined_vertex.assign(r.mesh.num_vertices(), 0);
  std::fill(r.refined_vertex.begin() + std::ptrdiff_t(before), r.refined_vertex.end(), char(1));
  // Further cycles: the first pass ranked its collapses before refinement had traced anything,
  // and refined on keys it could not revise. Collapsing a tenth of the budget again, now where the
  // refined mesh is smoothest (a split whose new vertex turned out to be predictable goes first),
  // and refining back on fresh keys moves triangles from where they turned out to buy little to
  // where they buy most (house_on_site 9.49% to 9.17% over four seeds; BENCHMARKS.md).
  for (int c = 0; c < o.auto_cycles && r.mesh.num_faces() == T && r.refine.splits > 0 && r.simplify.collapses > 0; ++c) {
    down.adaptive.budget = static_cast<size_t>((1 - o.auto_cycle_share) * double(T));
    down.simplify.max_surface_tolerance = down.simplify.surface_tolerance;
    const SimplifyStats first = r.simplify;  // the summary's: the first pass, with every pass's collapses
    std::vector<uint32_t> to;
    simplify_adaptively(scene, down, r, progress.add, &to, &source);
    if (!r.simplify.warning.empty()) r.warnings.pop_back();  // a target, as the share is
    const size_t collapses = r.simplify.collapses;
    const std::vector<uint32_t> moved = std::move(r.simplify.moved);
    r.simplify = first;
    r.simplify.collapses += collapses;
    r.auto_cycles += 1, r.auto_cycle_collapses += collapses;
    std::vector<char> refined(r.mesh.num_vertices(), 0);
    for (size_t i = 0; i < to.size() && i < r.refined_vertex.size(); ++i)
      if (to[i] != UINT32_MAX) refined[to[i]] = r.refined_vertex[i];
    for (uint32_t m : moved) refined[m] = 1;  // traced at a closest input point, as refinement's are
    const RefineStats so_far = r.refine;
    refine_adaptively(scene, o, r, &source);
    const RefineStats pass = r.refine;
    r.refine = so_far;
    add_refinement(r.refine, pass);
    refined.resize(r.mesh.num_vertices(), 1);
    r.refined_vertex = std::move(refined);
    if (collapses == 0) break;
  }
}

double surface_area(const Mesh& m) {
  double a = 0;
  for (const Triangle& t : m.triangles) {
    const double ta = triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2]));
    if (std::isfinite(ta)) a += ta;
  }
  return a;
}

// A second round of vertex rays: `budget` more where the planning variance costs most (each
// vertex to at most 16 times --rays), each vertex's rays continuing its own lattice.
void second_round(const RayScene& scene, const BakeOptions& o, const std::vector<double>& planning, double budget,
                  const BakeProgress& progress, Stopwatch& clock, BakeResult& r) {
  const TopUpPlan plan = plan_top_up(planning, r.vertex_rays, static_cast<uint64_t>(budget), vertex_areas(r.mesh), 16.0 * o.transfer.rays);
  if (progress.stage) progress.stage("vertex rays", plan.vertices);
  r.top_up = apply_top_up(r.mesh, scene, first_round(o), plan, r.transfer, r.point_variance, r.vertex_rays, progress.add, &r.point_halves);
  r.rays += r.top_up.rays;
  r.seconds_top_up = clock.lap();
}

// The values as the asset will hold them (AO clamped), for the hold-out error.
RowMatrixXd asset_values(const BakeOptions& o, const RowMatrixXd& values) {
  RowMatrixXd v = values;
  if (o.signal == AssetSignal::Ao) clamp_ao(v);
  return v;
}

// --error's measure must be sharp enough to act on and to state: its standard error at most
// kHoldoutPrecision of the estimate (the issue asks eval to confirm it within 25%: three standard
// errors). Where the screen stopped the pilot on a dense scan, the hold-out is the screen's 57,658
// samples at 32 rays, and armadillo's AO read 0.401% ± 0.136% against eval's 0.509%. There the
// terms' spread is the samples' noise (v far above the error), which falls as 1/rays, against
// 1/√samples for more samples: so the same samples are traced again (sharpen_holdout), with the
// rays that ratio asks for, at most 16 times the pilot's per sample in all and a quarter of the
// bake's rays so far per pass. Checked again after each round, as the error (and with it the
// precision the same spread gives) falls.
constexpr double kHoldoutPrecision = 0.08;
// A simplified asset's prediction is only stated, not acted on: a quarter of it will do.
constexpr double kSourcePrecision = 0.25;
// The hold-out's samples traced again until the prediction's standard error is at most
// `precision` of it (of `fallback` while it is 0), in passes of `retrace`; each pass's rays are
// counted in `*counted` too.
using Retrace = std::function<Holdout(const Holdout&, const TransferOptions&, TransferStats*)>;
void sharpen_prediction(const BakeOptions& o, double precision, double fallback, const Retrace& retrace, const BakeProgress& progress,
                        BakeResult& r, uint64_t* counted) {
  Holdout& h = r.fit_data.plan.holdout;
  if (h.rays <= 0 || h.size() == 0) return;
  const int unit = std::max(o.pilot.rays, 1), most = 16 * unit;
  // A few passes at most: each asks for the rays 1/rays predicts. Terms that are not all noise (a
  // shadow's interpolation error varies from sample to sample: mori_knob's AO) fall more slowly,
  // and where a pass took less than 30% off the standard error, more rays will not do: it stops.
  for (int pass = 0; pass < 4; ++pass) {
    const double e = r.predicted.percent > 0 ? r.predicted.percent : fallback;
    const double ratio = r.predicted.standard_error / (precision * e);
    if (!(ratio > 1) || h.rays >= most) return;
    // Whole multiples of the pilot's rays, at least one more.
    const double per_sample = std::min(0.25 * double(r.rays) / double(h.size()), double(most - h.rays));
    const int extra = std::min(int(std::ceil(double(h.rays) * (ratio - 1) / unit)) * unit, int(per_sample) / unit * unit);
    if (extra < unit) return;
    TransferOptions to = o.transfer;
    to.rays = extra;
    to.seed = mix64(mix64(o.transfer.seed ^ 0x4E1D0A7ull) + uint64_t(h.rays));  // independent of every earlier ray
    to.stream_offset = 0, to.streams = nullptr;
    if (progress.stage) progress.stage("hold-out", h.size());
    TransferStats st;
    h = retrace(h, to, &st);
    r.rays += st.rays, *counted += st.rays;
    const double before = r.predicted.standard_error;
    r.predicted = holdout_error(r.mesh, h, asset_values(o, r.transfer));
    if (r.predicted.standard_error > 0.7 * before) return;
  }
}

// Samples held out of the source surface, on which a simplified asset's error is predicted (as
// eval would measure it) and both ways chooses the fit's α as the default bake does
// (fit_bake_values): four per face of the asset (at least 4096, at most the pilot's
// hold-out; with one per face, mori_knob's predicted error had a standard error of 18% of it,
// 12% with four), traced at the pilot's rays with seeds no other rays share, each located on the
// asset by its closest facing point. The hold-out weighs each by the source area it stands for,
// as eval does. Where the transfer is dense already (chinese_dragon) no regulariser is best, where
// the vertices are noisy (bunny) a little is (docs/simplification.md).
Holdout source_holdout(const Mesh& source, const RayScene& scene, const Mesh& mesh, const BakeOptions& o, TransferStats* stats,
                       SurfaceSamples* drawn) {
  SampleOptions so;
  so.min_per_triangle = 0;
  const double wanted = double(std::min(o.pilot.holdout, std::max<size_t>(4096, 4 * mesh.num_faces())));
  so.per_triangle = wanted / double(std::max<size_t>(source.num_faces(), 1));
  so.seed = mix64(o.samples.seed + 0x401Dull);
  SurfaceSamples& s = *drawn;
  s = make_surface_samples(source, so);
  TransferOptions to = first_round(o);
  to.rays = std::max(o.pilot.rays, 2);
  to.seed = mix64(o.transfer.seed ^ 0x401D011ull);
  to.stream_offset = 0;
  std::vector<double> variance;
  const RowMatrixXd values = shadowed_transfer(scene, s.points, s.normals, to, stats, {}, &s.offsets, &variance);
  const std::vector<SurfaceLocation> at = closest_points(mesh, s.points, o.transfer.threads, &s.normals);
  Holdout h;
  h.rays = to.rays;
  h.face.resize(at.size());
  h.barycentric.resize(Eigen::Index(at.size()), 3);
  for (size_t k = 0; k < at.size(); ++k) h.face[k] = at[k].face, h.barycentric.row(Eigen::Index(k)) = at[k].barycentric.transpose();
  // Below one sample per source face, make_surface_samples' weights (a face's area over its
  // count) would count a large face's sample twice over: once in landing there (by area), again
  // in its weight. The samples are spread by area, so each stands for the same area (teapot at
  // 10%, 0.4 samples per source face: 4.09% predicted against eval's 6.49% with face weights).
  h.weight.assign(at.size(), at.empty() ? 0.0 : surface_area(source) / double(at.size()));
  h.variance = std::move(variance);
  h.values = values.cast<float>();
  return h;
}

// Sample j becomes sample order[j], for every per-sample array of s, in place: each cycle of the
// permutation is followed once, its first sample held aside.
void gather_rows_in_place(const std::vector<uint32_t>& order, SurfaceSamples& s) {
  std::vector<bool> done(order.size(), false);
  for (size_t j = 0; j < order.size(); ++j) {
    if (done[j]) continue;
    const Eigen::Index e = Eigen::Index(j);
    const Eigen::RowVector3d p = s.points.row(e), n = s.normals.row(e), o = s.offsets.row(e), b = s.barycentric.row(e);
    const uint32_t f = s.face[j];
    size_t k = j;
    for (size_t from = order[k]; from != j; k = from, from = order[k]) {
      const Eigen::Index to = Eigen::Index(k), at = Eigen::Index(from);
      s.points.row(to) = s.points.row(at), s.normals.row(to) = s.normals.row(at), s.offsets.row(to) = s.offsets.row(at);
      s.barycentric.row(to) = s.barycentric.row(at), s.face[k] = s.face[from];
      done[k] = true;
    }
    const Eigen::Index last = Eigen::Index(k);
    s.points.row(last) = p, s.normals.row(last) = n, s.offsets.row(last) = o, s.barycentric.row(last) = b, s.face[k] = f;
    done[k] = true;
  }
}

// Both ways samples the input's surface at this many times the samples per triangle asked. The
// default bake's pilot sends its samples to the faces where interpolation fails; these are spread
// over every face by area, so each face where they matter gets fewer. At about the same rays,
// twice the samples beat more vertex rays on every scene measured, on sibenik by 11%
// (BENCHMARKS.md, "Both ways: twice the samples"). A simplified asset gains little from them
// (chinese_dragon at 10%: 1%).
constexpr double kBothWaysSampleFactor = 2;

// Rays per sample of a simplified mesh's fit: half a vertex's, unless the user set the count.
// Its samples stand for the source's surface, and are not weighed against the vertices' point
// values by noise (a surviving vertex speaks for its point, not for the patch its faces now
// cover), so their noise goes straight into the asset: at 50% of bunny, 16 samples a face at 16
// rays each erred 2.574%, at 128 rays 1.311% (the input's own default bake: 1.247%). At equal
// rays, fewer samples with more rays each err less (the lattice of one point converges faster
// than samples spread apart: 1 at 256 rays, 1.740%; 16 at 16, 2.574%), so the rays per sample
// rise, not the count (BENCHMARKS.md, "The fit's samples of a simplified mesh"). Both ways at
// or above the input's count keeps --sample-rays: its fit is weighed by noise and its samples
// are twice the input's density, so more rays cost much and buy little (house_on_site, 8.668% at
// 16, 8.555% at 128); below it, it gains as a simplification does (bunny at 10%, 4.070% to 3.789%).
int fit_to_source_sample_rays(const BakeOptions& o, size_t asset_faces, size_t input_faces) {
  if (!o.sample_rays_auto || asset_faces >= input_faces) return o.sample_rays;
  return std::max(o.sample_rays, o.transfer.rays / 2);
}

// The fit of a simplified mesh: samples on the *source* surface (traced there, so they see the
// shading the asset must reproduce, never a point inside the original geometry), each located
// on the simplified surface by its closest point and weighted by that face's area over its
// count. As many samples as the fit would give the output's faces; faces that none reaches take
// the prior's interpolant. The samples keep their source points, normals and offsets (what is
// traced) with the simplified face's barycentrics (what the fit needs), so they are traced and
// reduced to face moments in one streaming pass, as every other fit's are. Not weighed by noise:
// a surviving vertex's traced value speaks for its point, not for the patch of source surface
// its faces now stand for.
void fit_to_source(const Mesh& source, const RayScene& scene, const BakeOptions& o, const BakeProgress& progress, Stopwatch& clock,
                   BakeResult& r) {
  const bool both_ways = o.refine == Refinement::Auto && r.refine.splits > 0;  // (when it only simplified, as a simplification)
  SurfaceSamples s;
  {
    SampleOptions so = o.samples;
    so.min_per_triangle = 0;
    if (both_ways) so.per_triangle *= kBothWaysSampleFactor, so.density *= kBothWaysSampleFactor;
    if (so.density <= 0) so.per_triangle *= double(r.mesh.num_faces()) / double(std::max<size_t>(source.num_faces(), 1));
    // Memory: both ways' conference has 10.6M samples. They are located in chunks, keeping only
    // each one's face and barycentrics, and then put in face order in place, so that no array is
    // ever held twice (copies side by side took conference's peak from 1.6 to 2.9 GB).
    s = make_surface_samples(source, so);
    s.barycentric.resize(0, 3), s.face = {}, s.weight = {}, s.begin = {};
    const size_t F = r.mesh.num_faces(), S = size_t(s.points.rows());
    s.face.resize(S), s.barycentric.resize(Eigen::Index(S), 3);
    constexpr size_t kChunk = size_t(1) << 20;
    const RayScene asset(r.mesh.positions, position_triangles(r.mesh));  // built once for every chunk
    for (size_t first = 0; first < S; first += kChunk) {
      const Eigen::Index at0 = Eigen::Index(first), n = Eigen::Index(std::min(kChunk, S - first));
      const RowMatrixX3d points = s.points.middleRows(at0, n), normals = s.normals.middleRows(at0, n);
      const std::vector<SurfaceLocation> at = closest_points(r.mesh, asset, points, o.transfer.threads, &normals);
      for (Eigen::Index i = 0; i < n; ++i) s.face[size_t(at0 + i)] = at[size_t(i)].face, s.barycentric.row(at0 + i) = at[size_t(i)].barycentric.transpose();
    }
    // Group by the face they landed on (a counting sort keeps the source order within a face).
    {
      const Buckets by_face = bucket_sort(F, S, 1, [&](size_t k, uint32_t) { return s.face[k]; });
      s.begin.assign(by_face.begin.begin(), by_face.begin.end());
      gather_rows_in_place(by_face.entry, s);
    }
    s.weight.resize(S);
    s.interpolated.assign(F, 0);
    for (size_t f = 0; f < F; ++f) {
      const size_t n = s.begin[f + 1] - s.begin[f];
      const Triangle& t = r.mesh.triangles[f];
      const double area = triangle_area(r.mesh.point(t[0]), r.mesh.point(t[1]), r.mesh.point(t[2]));
      if (n == 0) s.interpolated[f] = 1;
      for (size_t k = s.begin[f]; k < s.begin[f + 1]; ++k) s.weight[k] = area / double(n);
    }
  }
  TransferOptions to = o.transfer;
  to.rays = fit_to_source_sample_rays(o, r.mesh.num_faces(), source.num_faces());
  to.seed = mix64(o.transfer.seed ^ 0x5A3D1E5ull);
  to.stream_offset = 0;
  if (progress.stage) progress.stage("samples", s.size());
  TransferStats stats;
  r.fit_data.allocation = SampleAllocation::Area;
  r.fit_data.sample_rays = to.rays;
  r.fit_data.moments = trace_face_moments(r.mesh, scene, s, to, &stats, progress.add);
  r.fit_data.samples = std::move(s);
  r.fit_data.rays = stats.rays;
  r.rays += stats.rays;
  r.seconds_samples = clock.lap();
  if (both_ways && o.vertex_share > 0 && o.fit.method == FitMethod::LeastSquares) {
    // A second round of vertex rays, as the default bake's (fit): at most the vertices' own rays
    // again, where their noise costs most. Refinement's new vertices were traced at their closest
    // points on the input, not where they stand, so only the input's own vertices take part.
    std::vector<double> planning = smoothed_variance(r.mesh, r.point_variance, r.vertex_rays);
    double traced = 0;
    for (size_t i = 0; i < planning.size(); ++i) {
      if (i < r.refined_vertex.size() && r.refined_vertex[i]) planning[i] = 0;
      else traced += r.vertex_rays[i];
    }
    second_round(scene, o, planning, traced, progress, clock, r);
  }
  r.point = r.transfer;
  FitOptions fo = o.fit;
  // Both ways, the mesh keeps about the input's density: the ordinary fit's weight, weighed by
  // noise as it is (sibenik: 2.771% against 2.793% without noise weighing; docs/simplification.md).
  fo.alpha = both_ways ? o.fit.alpha : o.simplified_alpha;
  // The samples lie on the input, whose normals are not the asset's: t_u is not known there.
  fo.unshadowed_order = 0;
  // The hold-out: both ways chooses α on it; every least-squares fit here predicts its error on it.
  const bool held_out = fo.method == FitMethod::LeastSquares && r.fit_data.samples.size() > 0;
  SurfaceSamples drawn;
  if (held_out) {
    if (progress.stage) progress.stage("hold-out", 0);
    TransferStats held;
    r.fit_data.plan.holdout = source_holdout(source, scene, r.mesh, o, &held, &drawn);
    r.rays += held.rays;
  }
  if (held_out && both_ways && o.alpha_auto && !o.alpha_choices.empty()) {
    BakeOptions chosen = o;
    chosen.fit = fo;
    r.transfer = fit_bake_values(r.mesh, r.fit_data, r.point, r.point_variance, chosen, &r.fit, &r.alpha, &r.alpha_trials);
  } else {
    r.transfer = fit_vertex_values(r.mesh, r.fit_data.samples, r.fit_data.moments, r.point, fo, &r.fit, both_ways ? &r.point_variance : nullptr);
    r.alpha = fo.alpha;
  }
  if (held_out) {
    // Where the asset errs little, its hold-out's own noise (32 rays a sample) buries the error:
    // both ways on mori_knob predicted 0.209% +- 0.698% where eval at 4096 rays finds 0.997%. Its
    // samples are traced again until the standard error is at most a quarter of the prediction.
    r.predicted = holdout_error(r.mesh, r.fit_data.plan.holdout, asset_values(o, r.transfer));
    sharpen_prediction(o, kSourcePrecision, r.predicted.standard_error,
                       [&](const Holdout& h, const TransferOptions& more, TransferStats* st) {
                         return sharpen_holdout_at(drawn.points, drawn.normals, drawn.offsets, scene, h, more, st, progress.add);
                       },
                       progress, r, &r.holdout_sharpen_rays);
  }
  r.seconds_fit = clock.lap();
  if (!r.fit.warning.empty()) r.warnings.push_back(r.fit.warning);
}

void fit(const RayScene& scene, const BakeOptions& o, const BakeProgress& progress, Stopwatch& clock, BakeResult& r) {
  // The pilot weighs a face's residual against its corners' noise. Early stop leaves vertices
  // noisier where rays are dear, and the pilot would read that noise as hiding a shadow edge and
  // leave the face unsampled (conference: 9.4k faces against fixed --rays' 23.8k, 2.5% more
  // error). So it sees each vertex's variance at --rays, v·R_i/R: what interpolation would face had
  // every vertex traced them. The fit itself weighs by the real variance.
  std::vector<double> pilot_variance = r.point_variance;
  if (early_stop_on(o))
    for (size_t i = 0; i < pilot_variance.size(); ++i)
      if (r.vertex_rays[i] > 0 && r.vertex_rays[i] < o.transfer.rays) pilot_variance[i] *= r.vertex_rays[i] / o.transfer.rays;
  r.fit_data = sample_signal(r.mesh, scene, o, &r.transfer, &pilot_variance, progress);
  r.rays += r.fit_data.rays;
  r.seconds_samples = clock.lap();
  if (r.fit_data.allocation == SampleAllocation::Pilot && o.vertex_share > 0) {
    // The rays the pilot saved, against sampling every face: a share goes to the noisiest vertices.
    const double area_rays = (o.samples.density > 0 ? o.samples.density * surface_area(r.mesh) : o.samples.per_triangle * double(r.mesh.num_faces())) *
                             o.sample_rays;
    const double saved = std::max(0.0, area_rays - static_cast<double>(r.fit_data.rays));
    // At most the vertices' own rays again, so that --rays stays what sets a bake's cost: at the
    // default 256 the saved share is always below it (0.86 of it at most, on the shared scenes).
    double traced = 0;
    for (double v : r.vertex_rays) traced += v;
    second_round(scene, o, smoothed_variance(r.mesh, r.point_variance, r.vertex_rays), std::min(o.vertex_share * saved, traced), progress, clock, r);
  }
  if (o.transfer.log) o.transfer.log->barrier(true);  // a sharded bake: the rest is the merge's
  r.point = r.transfer;
  r.transfer = fit_bake_values(r.mesh, r.fit_data, r.point, r.point_variance, o, &r.fit, &r.alpha, &r.alpha_trials);
  r.seconds_fit = clock.lap();
  if (!r.fit.warning.empty()) r.warnings.push_back(r.fit.warning);
}

// The fit sees bounced light too: each surface sample gathers one bounce from the vertices'
// transfer before their last pass (so it gets every pass's light, as a vertex does), at the
// samples' own rays; those values, reduced to face moments, add to the direct moments, and the
// fit runs again with the vertices' bounced point values as its prior. A face whose bounced light
// varies inside it (a wall lit by a bright floor nearby) is then fitted as its direct light is,
// not interpolated from its corners. The moments' variances stay the direct ones'.
void fit_bounced_samples(const RayScene& scene, const BakeOptions& o, const BounceOptions& bounce, const RowMatrixXd& before_last,
                         const RowMatrixXd& fitted, const BakeProgress& progress, BakeResult& r) {
  const SurfaceSamples& s = r.fit_data.samples;
  BounceOptions b = bounce;
  b.rays = r.fit_data.sample_rays > 0 ? r.fit_data.sample_rays : o.sample_rays, b.seed = mix64(o.transfer.seed + 23);
  if (progress.stage) progress.stage("bounced samples", 0);
  TransferStats st;
  const RowMatrixXd g = gather_bounce(r.mesh, scene, before_last, s.points, s.normals, s.offsets, b, &st);
  r.rays += st.rays, r.bounce.rays += st.rays, r.bounce.sample_rays = st.rays;
  // Colour: the direct moments, prior and variances are every channel's (a variance summed over
  // 3·N² values is three times the one over N²: the weights' ratios stay).
  const int channels = b.colour ? 3 : 1;
  FaceMoments m = r.fit_data.moments;
  m.rows = m.rows.replicate(1, channels).eval();
  for (double& v : m.variance) v *= channels;
  std::vector<double> point_variance = r.point_variance;
  for (double& v : point_variance) v *= channels;
  const Eigen::Index K = g.cols();
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor> face(3, K);
  for (size_t f = 0; f + 1 < s.begin.size(); ++f) {
    if (s.begin[f] == s.begin[f + 1]) continue;
    sample_moments(s, s.begin[f], s.begin[f + 1], g.row(static_cast<Eigen::Index>(s.begin[f])).data(), K, face.data());
    m.rows.middleRows(static_cast<Eigen::Index>(3 * f), 3) += face;
  }
  // The prior: the point values with the bounced light the vertices' passes added to the fit.
  const RowMatrixXd prior = r.point.replicate(1, channels) + (r.transfer - fitted.replicate(1, channels));
  r.transfer = fit_vertex_values(r.mesh, s, m, prior, o.fit, &r.fit, &point_variance);
  if (!r.fit.warning.empty()) r.warnings.push_back(r.fit.warning);
}

// A sample round of --error: three times the fit's samples again, on the faces the pilot chose
// and by its weights, with seeds of their own, merged into the samples the fit has (face by
// face, count-weighted: still unbiased). Returns the samples added.
size_t add_samples(const RayScene& scene, const BakeOptions& o, int round, const BakeProgress& progress, BakeResult& r) {
  FitData& d = r.fit_data;
  SampleOptions so = o.samples;
  so.density = 0;
  so.per_triangle = 3.0 * double(d.samples.size()) / double(std::max<size_t>(r.mesh.num_faces(), 1));
  so.seed = mix64(o.samples.seed + 0x51A7ull + uint64_t(round));
  const SurfaceSamples more = make_surface_samples(r.mesh, so, d.plan.face_weight);
  TransferOptions to = o.transfer;
  to.rays = d.sample_rays;
  to.seed = mix64(mix64(o.transfer.seed ^ 0x5A3D1E5ull) + uint64_t(round));  // independent of every earlier ray
  to.stream_offset = 0;
  if (progress.stage) progress.stage("error target", more.size());
  TransferStats stats;
  const FaceMoments m = trace_face_moments(r.mesh, scene, more, to, &stats, progress.add);
  d.moments = merge_face_moments(d.samples, d.moments, more, m);
  d.samples = merge_surface_samples(d.samples, more);
  d.rays += stats.rays, r.rays += stats.rays, r.target_sample_rays += stats.rays;
  return more.size();
}

// The vertices' variances as the surface's noise: area-weighted (w, summing to `area`), and
// halved, as interpolation spreads a vertex's noise over its faces (∫_f h_c² = a_f/6).
double surface_noise(const std::vector<double>& w, double area, const std::vector<double>& variance) {
  double sum = 0;
  for (size_t i = 0; i < w.size(); ++i)
    if (std::isfinite(variance[i])) sum += w[i] * variance[i];
  return sum / (2 * std::max(area, 1e-300));
}

void sharpen_for_target(const RayScene& scene, const BakeOptions& o, const BakeProgress& progress, BakeResult& r) {
  if (r.simplified && r.simplify.collapses > 0) return;  // its hold-out lies on the source (fit_to_source sharpened it)
  sharpen_prediction(o, kHoldoutPrecision, o.target_error,
                     [&](const Holdout& h, const TransferOptions& to, TransferStats* st) { return sharpen_holdout(r.mesh, scene, h, to, st, progress.add); },
                     progress, r, &r.target_holdout_rays);
}

// --error E: more vertex rays, or more samples, until the hold-out error is at most E. The
// vertices' noise part of the squared error is N² = Σ_i w_i var_i / 2A (∫_f h_c² = a_f/6, w_i a
// third of the area around vertex i); the rest of the measured E² is interpolation error, which
// vertex rays do not lower. If E is above it, a round plans the water-filling budget whose
// planned noise meets E² − (E_now² − N²), at most doubling the rays the vertices hold, and
// traces it, continuing each vertex's lattice. If not,
// a round gives the fit four times the samples on the faces the pilot chose, until a round
// lowers the error by less than 3% (what is left is the piecewise-linear interpolant's own limit,
// or sits on faces the pilot left to interpolation: refinement's job). Each round fits again and
// measures again on the hold-out samples.
void reach_target(const RayScene& scene, const BakeOptions& o, const BakeProgress& progress, Stopwatch& clock, BakeResult& r) {
  if (r.fit_data.allocation != SampleAllocation::Pilot) {
    r.warnings.push_back("--error needs the pilot's held-out samples to measure the error; ignored with this sample allocation");
    return;
  }
  const std::vector<double> w = vertex_areas(r.mesh);
  double area = 0;
  for (double a : w) area += a;
  const double unit = unshadowed_norm(o.transfer.order) / 100, target2 = std::pow(o.target_error * unit, 2);
  const double max_rays = 64.0 * o.transfer.rays;
  const int kMaxSampleRounds = 2;
  bool samples_spent = r.fit_data.plan.sampled_faces == 0;
  sharpen_for_target(scene, o, progress, r);
  for (int round = 1; round <= 6 && r.predicted.percent > o.target_error; ++round) {
    const double noise2 = surface_noise(w, area, r.point_variance);
    const double bias2 = std::max(0.0, std::pow(r.predicted.percent * unit, 2) - noise2);
    if (target2 <= 1.02 * bias2) {
      if (samples_spent || r.target_sample_rounds >= kMaxSampleRounds) {
        char buf[260];
        std::snprintf(buf, sizeof buf, "--error %g: %.3f%% of the error is interpolation, which more vertex rays do not lower%s; refine "
                      "(--refine adaptive --budget) or sample more faces (--pilot-significance)", o.target_error, std::sqrt(bias2) / unit,
                      r.target_sample_rounds ? " and more samples no longer did" : "");
        r.warnings.push_back(buf);
        break;
      }
      const double before = r.predicted.percent;
      r.target_samples += add_samples(scene, o, ++r.target_sample_rounds, progress, r);
      r.transfer = fit_vertex_values(r.mesh, r.fit_data.samples, r.fit_data.moments, r.point, o.fit, &r.fit, &r.point_variance);
      r.predicted = holdout_error(r.mesh, r.fit_data.plan.holdout, asset_values(o, r.transfer));
      samples_spent = r.predicted.percent > 0.97 * before;
      sharpen_for_target(scene, o, progress, r);
      continue;
    }
    const double want = 2 * area * (target2 - bias2);  // Σ w var the noise may have
    const std::vector<double> planning = smoothed_variance(r.mesh, r.point_variance, r.vertex_rays);
    TopUpPlan plan = plan_top_up_to_variance(planning, r.vertex_rays, want, r.point_variance, w, max_rays);
    // At most as many rays as the vertices hold: near the interpolation floor the room E² − bias²
    // is a small difference of two measured numbers, and a plan sized on it alone can be many
    // times what the target needs (armadillo's AO, seed 2: 423M rays for 0.395% against the 0.45%
    // asked). A round then measures again, and the next plans on what it found.
    double held = 0;
    for (double v : r.vertex_rays) held += v;
    if (double(plan.rays) > held) plan = plan_top_up(planning, r.vertex_rays, uint64_t(held), w, max_rays);
    if (plan.rays == 0) break;
    if (progress.stage) progress.stage("error target", plan.vertices);  // each vertex's lattice continued
    const TopUpStats st = apply_top_up(r.mesh, scene, first_round(o), plan, r.point, r.point_variance, r.vertex_rays, progress.add, &r.point_halves);
    r.rays += st.rays, r.target_rays += st.rays, ++r.target_rounds;
    r.transfer = fit_vertex_values(r.mesh, r.fit_data.samples, r.fit_data.moments, r.point, o.fit, &r.fit, &r.point_variance);
    r.predicted = holdout_error(r.mesh, r.fit_data.plan.holdout, asset_values(o, r.transfer));
    sharpen_for_target(scene, o, progress, r);
  }
  if (r.predicted.percent > o.target_error && r.warnings.empty()) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "--error %g: reached %.3f%% (at most %g rays per vertex)", o.target_error, r.predicted.percent, max_rays);
    r.warnings.push_back(buf);
  }
  r.seconds_target = clock.lap();
}

// The bounce passes from the direct asset values `fitted`, at b.rays per vertex, then (by default)
// once more at the fit's samples and the fit again: r.transfer becomes the bounced asset.
void run_bounces(const RayScene& bounce_scene, const BakeOptions& o, const BounceOptions& b, const RowMatrixXd& fitted, const BakeProgress& progress,
                 BakeResult& r) {
  if (progress.stage) progress.stage("bounces", 0);
  BounceStats st;
  RowMatrixXd before_last;
  r.transfer = interreflected_transfer(r.mesh, bounce_scene, fitted, b, &st, &before_last);
  const uint64_t earlier = r.bounce.rays;
  r.bounce = st, r.bounce.rays += earlier, r.rays += st.rays, r.bounce_rays = b.rays;
  const bool on_own_samples = !(r.simplified && r.simplify.collapses > 0);  // else the samples lie on the input
  if (o.bounce.fit_samples && o.fit.method != FitMethod::Point && r.fit_data.samples.size() > 0 && on_own_samples && r.bounce.passes > 0)
    fit_bounced_samples(bounce_scene, o, b, before_last, fitted, progress, r);
}

// --error with bounces, before the passes run: their rays per vertex. They start at the direct
// light's count; where the target leaves room, fewer: the least power of two, at least 8, whose
// predicted noise (bounce_noise ahead of the passes, falling as 1/R) takes at most a quarter of
// the room the direct light leaves, E² − E_direct². The rest of the room is for what the bounces'
// interpolation adds, which is not known before they run. Never more: the rounds after the
// passes add rays where the measured error asks for them.
int choose_bounce_rays(const Mesh& mesh, const RayScene& scene, const RowMatrixXd& direct, const BounceOptions& b, double room,
                       uint64_t* rays) {
  if (!(room > 0) || b.rays <= 8) return b.rays;
  const double noise = bounce_noise(mesh, scene, direct, b, 2048, rays);
  int r = b.rays;
  while (r / 2 >= 8 && noise * b.rays / (r / 2) <= 0.25 * room) r /= 2;
  return r;
}

// --error with bounces: the target holds for the bounced asset, whose error the hold-out measures
// against bounced light traced as paths (bounced_holdout: eval's reference, never the asset). The
// bounced error has three parts: the direct light's (its noise and interpolation, which the
// bounces carry along), the bounce passes' own noise (R rays per vertex and pass), and what the
// bounces' interpolation adds. While it is above the target, the excess Δ = E_b² − E² goes to
// whichever of the two rays can lower it at the smaller cost, each costed with the passes it
// makes run again:
//   - the passes' rays: their noise N_b (bounce_noise: two gathers of seeds of their own) falls as 1/R, so
//     R·N_b/(N_b − Δ) rays remove Δ; the passes then run again at that count, every pass of them
//     (once with the hit cache) plus the fit samples' bounce;
//   - the direct light's rays: reach_target again at the direct error that leaves room for Δ (its
//     noise N_d must hold Δ), then the passes again at their count.
// When neither noise holds Δ the excess is interpolation, which rays do not lower: a warning
// says to refine, as reach_target's does.
void reach_bounced_target(const RayScene& scene, const RayScene& bounce_scene, const BakeOptions& o, const BounceOptions& bounce, RowMatrixXd fitted,
                          const BakeProgress& progress, Stopwatch& clock, BakeResult& r) {
  BounceOptions b = bounce;
  PathOptions po;
  po.order = o.transfer.order, po.paths = o.target_paths, po.bounces = r.bounce.passes, po.albedo = b.albedo, po.colour = b.colour;
  po.seed = mix64(o.transfer.seed ^ 0xB0CE5401Dull), po.threads = o.transfer.threads;  // independent of every bake ray
  if (progress.stage) progress.stage("bounced hold-out", 0);
  // A quarter of the points first: a loose target is told from the error at once; within three
  // standard errors of E, the whole subset (four times the points, half the standard error).
  r.predicted_direct = r.predicted;
  Holdout held;
  for (size_t points = std::max<size_t>(1, o.target_paths_points / 4);; points = o.target_paths_points) {
    TransferStats st;
    held = bounced_holdout(r.mesh, bounce_scene, holdout_subset(r.fit_data.plan.holdout, points), po, &st);
    r.rays += st.rays, r.target_holdout_rays += st.rays;
    r.predicted = holdout_error(r.mesh, held, r.transfer);
    if (points >= o.target_paths_points || held.size() >= r.fit_data.plan.holdout.size() ||
        std::abs(r.predicted.percent - o.target_error) > 3 * r.predicted.standard_error)
      break;
  }
  const std::vector<double> w = vertex_areas(r.mesh);
  double area = 0;
  for (double a : w) area += a;
  const double unit = unshadowed_norm(o.transfer.order) / 100;
  const double V = double(r.mesh.num_vertices()), pass_cost = r.bounce.cached ? 1.0 : std::max(r.bounce.passes, 1);
  const double sample_cost = double(r.fit_data.samples.size()) * std::max(r.fit_data.sample_rays, 1);
  for (int round = 1; round <= 4 && r.predicted.percent > o.target_error; ++round) {
    const double excess = std::pow(r.predicted.percent * unit, 2) - std::pow(o.target_error * unit, 2);
    uint64_t noise_rays = 0;
    BounceOptions run = b;
    run.bounces = r.bounce.passes;
    const double nb = bounce_noise(r.mesh, bounce_scene, fitted, run, o.target_paths_points / 4, &noise_rays);
    r.rays += noise_rays, r.target_holdout_rays += noise_rays;
    const double nd = surface_noise(w, area, r.point_variance);
    const double rebounce = V * b.rays * pass_cost + (o.bounce.fit_samples ? sample_cost : 0);
    // The passes' rays: enough to remove Δ where their noise holds it, else a quadrupling.
    // bounce_noise is an estimate from above (1.2-2.3× the passes' noise, ScenesBounceNoise): the
    // passes' rays are bought only when a fraction kLow of it still holds Δ, and sized for that
    // fraction. And only where the vertices' bounced values are the asset's: when the fit's
    // samples gather their own bounce and the fit runs again (the default), it averages the
    // vertices' bounce noise away, and more bounce rays at the vertices barely move the asset
    // (tried on conference: a round of 4× the bounce rays, which their noise said would reach the
    // target, lowered the error by a few hundredths of a percent).
    constexpr double kLow = 0.4;
    const bool fitted_bounce = o.bounce.fit_samples && o.fit.method != FitMethod::Point && r.fit_data.samples.size() > 0;
    const double low = fitted_bounce ? 0 : kLow * nb;
    const double factor_b = low > 1.05 * excess ? low / (low - excess) : 4;
    int rays_b = b.rays;
    while (rays_b < b.rays * factor_b && rays_b < std::min(16 * bounce.rays, 1 << 16)) rays_b *= 2;
    const double cost_b = V * rays_b * pass_cost + (o.bounce.fit_samples ? sample_cost : 0);
    // The direct rays: the vertex rays traced so far, times what the same 1/R law asks.
    double traced = 0;
    for (double n : r.vertex_rays) traced += n;
    const double cost_d = nd > 1.05 * excess ? traced * excess / (nd - excess) + rebounce : INFINITY;
    const bool bounce_can = rays_b > b.rays && low > 1.05 * excess, direct_can = std::isfinite(cost_d);
    // Neither alone: the passes' noise cut to a quarter, and the direct light's for the rest.
    const double rest = excess - 0.75 * low;
    const bool both = !bounce_can && !direct_can && b.rays * 4 <= std::min(16 * bounce.rays, 1 << 16) && nd > 1.05 * rest;
    if (!bounce_can && !direct_can && !both) {
      char buf[300];
      std::snprintf(buf, sizeof buf, "--error %g: the bounced asset's %.3f%% is mostly interpolation (its noise: direct %.3f%%, bounces %.3f%%), "
                    "which more rays do not lower; refine (--refine adaptive --budget)", o.target_error, r.predicted.percent,
                    std::sqrt(nd) / unit, std::sqrt(nb) / unit);
      r.warnings.push_back(buf);
      break;
    }
    const double before = std::pow(r.predicted.percent * unit, 2);
    double expected;
    if (bounce_can && (!direct_can || cost_b <= cost_d)) {
      expected = low * (1 - double(b.rays) / rays_b);
      b.rays = rays_b;
      ++r.target_bounce_rounds;
    } else {
      if (both) b.rays *= 4, ++r.target_bounce_rounds;
      // The direct asset aimed at the error that leaves the rest of Δ to the other parts.
      BakeOptions direct = o;
      const double cut = both ? rest : excess;
      expected = both ? excess : cut;
      direct.target_error = std::sqrt(std::max(0.0, std::pow(r.predicted_direct.percent * unit, 2) - cut)) / unit;
      r.transfer = fitted;
      r.predicted = r.predicted_direct;
      const size_t said = r.warnings.size();
      reach_target(scene, direct, progress, clock, r);
      r.warnings.resize(said);  // its target is this loop's, not the user's: judged below
      fitted = r.transfer, r.predicted_direct = r.predicted;
      ++r.target_direct_rounds;
    }
    run_bounces(bounce_scene, o, b, fitted, progress, r);
    r.predicted = holdout_error(r.mesh, held, r.transfer);
    // The noise model is only a model: rays that lowered the measured error by less than a
    // quarter of what it promised will not do better next round.
    if (before - std::pow(r.predicted.percent * unit, 2) < 0.25 * expected && r.predicted.percent > o.target_error) {
      char buf[300];
      std::snprintf(buf, sizeof buf, "--error %g: more rays lowered the bounced asset's error only to %.3f%%; the rest is interpolation, "
                    "which rays do not lower; refine (--refine adaptive --budget)", o.target_error, r.predicted.percent);
      r.warnings.push_back(buf);
      break;
    }
  }
  if (r.predicted.percent > o.target_error) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "--error %g: the bounced asset reached %.3f%% (bounce passes at %d rays per vertex)", o.target_error,
                  r.predicted.percent, b.rays);
    bool said = false;
    for (const std::string& m : r.warnings) said = said || m.rfind("--error", 0) == 0;
    if (!said) r.warnings.push_back(buf);
  }
}

}  // namespace

RowMatrixXd fit_bake_values(const Mesh& mesh, const FitData& data, const RowMatrixXd& prior, const std::vector<double>& prior_variance,
                            const BakeOptions& o, FitStats* stats, double* alpha, std::vector<std::pair<double, double>>* trials) {
  const std::vector<double>* variance = prior_variance.size() == mesh.num_vertices() ? &prior_variance : nullptr;
  // (Without samples — the pilot's screen stopped it, or it found no face — nothing is fitted
  // and every α gives the same values: no trials.)
  const bool choose = o.alpha_auto && o.fit.method == FitMethod::LeastSquares && data.plan.holdout.size() > 0 && !o.alpha_choices.empty() && data.samples.size() > 0;
  if (alpha) *alpha = o.fit.alpha;
  if (trials) trials->clear();
  if (!choose) return fit_vertex_values(mesh, data.samples, data.moments, prior, o.fit, stats, variance);
  // One corrected prior for every candidate: the projection does not depend on α.
  FitStats known;
  const RowMatrixXd base = fit_prior(mesh, prior, o.fit, &known);
  FitOptions f = o.fit;
  f.unshadowed_order = 0;
  RowMatrixXd best;
  for (double a : o.alpha_choices) {
    f.alpha = a;
    FitStats st;
    RowMatrixXd x = asset_values(o, fit_vertex_values(mesh, data.samples, data.moments, base, f, &st, variance));
    if (trials) trials->emplace_back(a, holdout_error(mesh, data.plan.holdout, x).percent);
    // Ascending choices: more smoothing only where the hold-out can tell it is better (its gain
    // over the fit kept, paired on the same samples, above twice its standard error); past that
    // it only adds bias, and a gain within the hold-out's noise is no reason to smooth.
    if (best.size() > 0) {
      const ErrorDifference gain = holdout_difference(mesh, data.plan.holdout, best, x);
      if (!(gain.mean > 2 * gain.standard_error)) break;
    }
    best = std::move(x);
    if (alpha) *alpha = a;
    if (stats) *stats = st;
  }
  if (stats) stats->unshadowed_iterations = known.unshadowed_iterations, stats->seconds_unshadowed = known.seconds_unshadowed;
  return best;
}

FitData sample_signal(const Mesh& mesh, const RayScene& scene, const BakeOptions& in, const RowMatrixXd* prior,
                      const std::vector<double>* prior_variance, const BakeProgress& progress) {
  const BakeOptions o = resolve_bake_options(in);
  const Stopwatch clock;
  FitData d;
  TransferOptions to = o.transfer;
  to.rays = o.sample_rays;
  to.seed = mix64(o.transfer.seed ^ 0x5A3D1E5ull);  // independent of the vertices' rays
  to.stream_offset = 0;
  SampleOptions so = o.samples;
  d.allocation = o.allocation == SampleAllocation::Pilot && o.pilot.rays >= 2 && prior && prior_variance
                     ? SampleAllocation::Pilot : SampleAllocation::Area;
  if (d.allocation == SampleAllocation::Pilot) {
    TransferOptions pilot_rays = to;
    pilot_rays.seed = mix64(o.transfer.seed ^ 0x9170Dull);  // independent of the samples' rays
    const SurfaceSamples pilot = make_pilot_samples(mesh, o.pilot, mix64(o.samples.seed + 1));
    if (progress.stage) progress.stage("pilot", pilot.size());
    d.plan = plan_samples(mesh, scene, pilot, *prior, *prior_variance, pilot_rays, o.pilot, progress.add);
    // The sampled faces' pilot samples count towards their share of the budget, up to half of it.
    // The budget has the pilot's floor: on a coarse mesh a face crossed by a shadow needs many
    // samples to place it, and a few thousand cost nothing against a bake's fixed costs.
    double budget = so.density > 0 ? so.density * d.plan.sampled_area : so.per_triangle * double(d.plan.sampled_faces);
    if (d.plan.sampled_faces > 0) budget = std::max(budget, static_cast<double>(o.pilot.min_samples));
    const double wanted = std::max(0.5 * budget, budget - o.pilot.per_triangle * double(d.plan.sampled_faces));
    // The same sample rays (`wanted` samples at sample_rays each), split as the pilot's
    // measurements say: fewer rays and more samples where a shadow crosses large faces.
    if (!d.plan.sample_rays.noise.empty() && wanted > 0) {
      choose_sample_rays(d.plan.sample_rays, wanted * double(o.sample_rays) / double(d.plan.sampled_faces), o.sample_rays);
      to.rays = d.plan.sample_rays.rays;
    }
    so.density = 0;
    so.per_triangle = mesh.num_faces() ? std::max(0.0, wanted) * double(o.sample_rays) / double(to.rays) / double(mesh.num_faces()) : 0;
    d.samples = make_surface_samples(mesh, so, d.plan.face_weight);
    d.rays += d.plan.rays;
  } else {
    d.samples = make_surface_samples(mesh, so);
  }
  if (progress.stage) progress.stage("samples", d.samples.size());
  TransferStats stats;
  d.sample_rays = to.rays;
  d.moments = trace_face_moments(mesh, scene, d.samples, to, &stats, progress.add);
  d.rays += stats.rays;
  d.seconds = clock.total();
  return d;
}

BakeResult bake(const Mesh& mesh, const BakeOptions& options, const BakeProgress& progress) {
  BakeOptions o = resolve_bake_options(options);
  check_bake_options(o);
  if (o.transfer.log) check_fixed_mesh(o);
  if (o.albedo_colour.coloured()) {  // missing colours or UVs fail before any ray, naming the input
    try {
      AlbedoField(mesh, o.albedo_colour);
    } catch (const InputError& e) {
      throw InputError((o.source.empty() ? std::string("the input") : o.source) + ": " + e.what());
    }
  }
  Stopwatch clock;
  BakeResult r;
  r.mesh = o.refine == Refinement::Uniform ? refine_uniform(mesh, o.uniform) : mesh;
  r.seconds_refine = clock.lap();
  const RayScene scene(r.mesh.positions, position_triangles(r.mesh));
  r.seconds_scene = clock.lap();
  TransferStats stats;
  const RowMatrixX3d offsets = vertex_offset_directions(r.mesh);
  if (o.sg_lobes > 0) {
    bake_lobes(scene, offsets, o, progress, clock, r);
    r.seconds_total = clock.total();
    r.metadata = bake_metadata(o, r);
    return r;
  }
  if (o.order_auto) {
    // Before anything is traced: every later stage (and every shard) runs at the chosen order.
    if (progress.stage) progress.stage("order", 0);
    r.order = choose_order(scene, vertex_positions(r.mesh), r.mesh.normals, offsets, o.transfer, o.order_choice);
    o.transfer.order = r.order.order;
    o = resolve_bake_options(o);  // the fit's known part at the chosen order
    r.rays += r.order.rays;
    clock.lap();
  }
  if (o.target_error > 0 && o.rays_auto && !o.transfer.log) {
    // A loose target needs few rays: the first round takes what a pilot of vertices predicts.
    if (progress.stage) progress.stage("first round", 0);
    // The pilot's second round of vertex rays spends up to as many again: judged at twice the rays.
    const bool second = o.fit.method != FitMethod::Point && o.allocation == SampleAllocation::Pilot && o.vertex_share > 0;
    r.first_round = choose_first_rays(r.mesh, scene, o.transfer, o.target_error / std::sqrt(2.0), unshadowed_norm(o.transfer.order) / 100,
                                      {32, 64, 128, 256}, second ? 2.0 : 1.0);
    o.transfer.rays = r.first_round.rays;
    r.rays += r.first_round.pilot_rays;
    o = resolve_bake_options(o);
  }
  if (progress.stage) progress.stage("transfer", r.mesh.num_vertices());
  const TransferOptions first = first_round(o);
  r.transfer = shadowed_transfer(scene, vertex_positions(r.mesh), r.mesh.normals, first, &stats, progress.add, &offsets, &r.point_variance,
                                 &r.point_halves);
  r.rays += stats.rays;
  r.vertex_rays.assign(r.mesh.num_vertices(), first.rays);
  if (early_stop_on(o)) {  // the order is known: so is the variance to stop at
    const double stop = std::pow(o.stop_noise_percent / 100 * unshadowed_norm(o.transfer.order), 2);
    if (progress.stage) progress.stage("early stop", 0);
    std::function<void()> barrier;
    if (o.transfer.log) barrier = [&] { o.transfer.log->barrier(false); };
    r.early_stop = early_stop_vertices(r.mesh, scene, first, o.transfer.rays, stop, r.transfer, r.point_variance, r.vertex_rays, barrier, progress.add,
                                       &r.point_halves);
    r.rays += r.early_stop.rays;
  }
  r.seconds_transfer = clock.lap();
  if (o.refine == Refinement::Adaptive) {
    if (o.adaptive.budget < r.mesh.num_faces()) {
      if (progress.stage) progress.stage("simplify", 0);
      simplify_adaptively(scene, o, r, progress.add);
    } else if (o.rekey_share > 0 && o.rekey_share < 1 && o.bounce.bounces > 0 &&
               static_cast<size_t>(o.rekey_share * double(o.adaptive.budget)) > r.mesh.num_faces()) {
      refine_rekeyed(scene, o, progress, r);
    } else {
      refine_adaptively(scene, o, r);
    }
    r.seconds_refine = clock.lap();
  }
  if (o.refine == Refinement::Auto) {
    refine_both_ways(mesh, scene, o, progress, r);
    r.seconds_refine = clock.lap();
  }
  // New vertices have no halves, and the old ones need not keep their rows: unknown from here.
  if (r.point_halves.rows() != Eigen::Index(r.mesh.num_vertices()) || o.refine != Refinement::None)
    r.point_halves = RowMatrixXd::Constant(Eigen::Index(r.mesh.num_vertices()), r.transfer.cols(), NAN);
  if (o.transfer.log && o.fit.method == FitMethod::Point) o.transfer.log->barrier(true);
  if (o.refine_only) {  // --stage refine: the mesh and its point values, for later bakes
    r.point = r.transfer;
    r.seconds_total = clock.total();
    r.metadata = bake_metadata(o, r);
    return r;
  }
  if (o.fit.method != FitMethod::Point) {
    if (r.simplified && r.simplify.collapses > 0) {
      // Its hold-out lies on the input's surface; fit_to_source predicts the error on it.
      fit_to_source(mesh, scene, o, progress, clock, r);
      if (o.refine == Refinement::Auto && r.refine.splits > 0) o.fit.alpha = r.alpha;  // the bounced fit keeps it
    } else {
      fit(scene, o, progress, clock, r), o.fit.alpha = r.alpha;  // the --error rounds and the bounced fit keep it
      if (r.fit_data.allocation == SampleAllocation::Pilot || r.fit_data.plan.holdout.size() > 0)
        r.predicted = holdout_error(r.mesh, r.fit_data.plan.holdout, asset_values(o, r.transfer));
    }
  }
  if (r.point.size() == 0) r.point = r.transfer;
  if (o.target_error > 0) reach_target(scene, o, progress, clock, r);
  if (o.bounce.bounces > 0) {
    BounceOptions b = o.bounce;
    if (b.until_converged) {  // the bake's own noise, in eval's unit, as the stopping point
      const std::vector<double> area = vertex_areas(r.mesh);
      double num = 0, den = 0;
      for (size_t i = 0; i < area.size(); ++i)
        if (std::isfinite(r.point_variance[i])) num += area[i] * r.point_variance[i], den += area[i];
      b.noise_percent = 100 * std::sqrt(num / std::max(den, 1e-300)) / unshadowed_norm(o.transfer.order);
    }
    if (o.albedo_colour.coloured()) b.colour = std::make_shared<const AlbedoField>(r.mesh, o.albedo_colour);
    // A bounce reads the values of the triangle a ray hits, so the scene must hold the asset's own
    // triangles: after adaptive refinement or simplification it is built again (visibility alone,
    // as every stage before needed, does not care which triangles tile the surface).
    const std::unique_ptr<RayScene> own = scene_for(r.mesh, scene, o);
    const RayScene& bounce_scene = own ? *own : scene;
    const RowMatrixXd fitted = r.transfer;
    const bool on_own_samples = !(r.simplified && r.simplify.collapses > 0);
    const bool target = o.target_error > 0 && on_own_samples && r.fit_data.allocation == SampleAllocation::Pilot && r.fit_data.plan.holdout.size() > 0;
    if (target && !b.until_converged) {
      const double unit = unshadowed_norm(o.transfer.order) / 100;
      const double room = std::pow(o.target_error * unit, 2) - std::pow(r.predicted.percent * unit, 2);
      if (progress.stage) progress.stage("bounce rays", 0);
      uint64_t noise_rays = 0;
      b.rays = choose_bounce_rays(r.mesh, bounce_scene, fitted, b, room, &noise_rays);
      r.rays += noise_rays, r.target_holdout_rays += noise_rays;
    }
    r.bounce_rays_chosen = b.rays;
    run_bounces(bounce_scene, o, b, fitted, progress, r);
    if (target) reach_bounced_target(scene, bounce_scene, o, b, fitted, progress, clock, r);
    if (b.colour) r.albedo = b.colour->vertices();
    r.seconds_bounce = clock.lap();
  }
  if (o.albedo_colour.coloured() && r.albedo.rows() == 0) r.albedo = AlbedoField(r.mesh, o.albedo_colour).vertices();
  if (o.signal == AssetSignal::Ao) {
    // The paper's choice: clamp after the fit (a constrained solve is rarely worth it).
    r.clamped = clamp_ao(r.transfer);
    clamp_ao(r.point);
  }
  r.seconds_total = clock.total();
  r.metadata = bake_metadata(o, r);
  return r;
}

}  // namespace prtsub
