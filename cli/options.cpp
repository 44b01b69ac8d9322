#include "cli/options.h"

#include <cmath>
#include <cstdlib>

#include "cli/specs.h"
#include "cli/images.h"
#include "prtsub/prt/sg_basis.h"
#include "prtsub/prt/sh.h"

namespace prtsub {

void add_transfer_options(ArgParser& args, TransferOptions& t, bool with_order) {
  if (with_order) args.option("--order", "N", "SH order: N bands, N² coefficients", &t.order, 1, kMaxShOrder);
  args.option("--rays", "R", "rays per point", &t.rays, 1, 1 << 20);
  args.option("--seed", "S", "random seed; results depend on it, not on threads", &t.seed);
  add_threads_option(args, t.threads);
}

namespace {
const char* denominator_name(ProgressiveOptions::Denominator d) {
  return d == ProgressiveOptions::Denominator::Interpolated ? "interpolated" : d == ProgressiveOptions::Denominator::Clamped ? "clamped" : "running";
}
const char* update_name(bool gauss_seidel) { return gauss_seidel ? "gauss-seidel" : "jacobi"; }
}  // namespace

void add_estimator_options(ArgParser& args, TransferOptions& t) {
  args.choice("--estimator", "how each point's rays become coefficients: cv, the control variate; mc, plain Monte Carlo\n"
              "projection; pls, the progressive least-squares encoder; pls-cv, that encoder on the blocked part only\n"
              "(docs/transfer.md)", &t.estimator,
              {TransferEstimator::ControlVariate, TransferEstimator::MonteCarlo, TransferEstimator::Progressive, TransferEstimator::ProgressiveBlocked},
              estimator_name);
  args.option("--pls-acceleration", "A", "pls: the encoder's acceleration factor [default 1]", &t.progressive.acceleration, 1e-3, 100.0);
  args.choice("--pls-update", "pls: residual updated after each coefficient, or once per sample", &t.progressive.gauss_seidel,
              {true, false}, update_name);
  args.choice("--pls-denominator", "pls: ∫B² from the samples so far, blended from a bound (the paper's fix), or floored",
              &t.progressive.denominator,
              {ProgressiveOptions::Denominator::Interpolated, ProgressiveOptions::Denominator::Running, ProgressiveOptions::Denominator::Clamped},
              denominator_name);
}

void add_threads_option(ArgParser& args, int& threads) {
  args.option("--threads", "T", "worker threads, 0 for every core; results do not depend on it", &threads, 0, 1024);
}

void add_batch_option(ArgParser& args, RefineOptions& refine) {
  args.option("--batch", "B", "adaptive: faces split per Embree batch", &refine.batch, size_t(1), size_t(1) << 20);
}

void add_report_option(ArgParser& args, std::string& path) {
  args.option("--report", "R.json", "also write the summary's figures as flat JSON", &path);
}

void BakeCli::add_common(ArgParser& args) {
  args.positional("INPUT", "mesh file: .obj, .ply (ASCII or binary), .off or .stl", &input);
  args.option("--crease-angle", "DEG", "computed normals: sharper edges are creases; 0 is flat shading", &load.crease_angle_deg,
              0.0, 180.0);
  args.option("--order", "N|auto", "SH order: N bands, N² coefficients; auto: the lowest order whose truncation error is\n"
              "below the bake's own noise (or --order-tolerance), from a pilot of the vertices [default 4]", &order_);
  args.option("--max-order", "M", "--order auto: the highest order considered", &bake.order_choice.max_order, 2, kMaxShOrder);
  args.option("--order-tolerance", "E", "--order auto: keep the truncation error under E percent of ||t_unshadowed|| (0: the\n"
              "bake's noise)", &bake.order_choice.tolerance_percent, 0.0, 100.0);
  args.option("--order-light", "SPEC", "--order auto: errors under this light turned any way (the --light syntax of render;\n"
              "lights add up) instead of the worst light, eval's metric", &order_lights_);
  add_transfer_options(args, bake.transfer, false);
  add_estimator_options(args, bake.transfer);
  args.when_given("--rays", [this] { rays_given_ = true; });
  args.when_given("--sample-rays", [this] { sample_rays_given_ = true; });
  args.option("--first-rays", "R", "per-vertex early stop: each vertex traces R rays (even), then doubles them while a\n"
              "doubling is worth its rays, up to --rays", &bake.round_rays, 2, 1 << 20);
  args.option("--ray-noise", "P", "early stop: the price of a doubling, as the noise (percent of ||t_unshadowed||) at which\n"
              "a vertex of mean area stops at --rays", &bake.stop_noise_percent, 0.0, 100.0);
  args.option("--rays-fixed", "R", "every vertex traces exactly R rays, no early stop (--rays and --first-rays are ignored)",
              &rays_fixed_, 1, 1 << 20);
  add_report_option(args, report);
}

void require_fixed_order(const BakeOptions& o, const char* command) {
  if (o.order_auto) throw UsageError(std::string(command) + ": --order auto is for bake; give a number");
}

void BakeCli::add_fit(ArgParser& args) {
  FitOptions& f = bake.fit;
  SampleOptions& s = bake.samples;
  args.choice("--signal", "what to bake: SH transfer, or ambient occlusion (one ao value)", &bake.signal,
              {AssetSignal::Transfer, AssetSignal::Ao}, asset_signal_name);
  args.option("--bounces", "N|auto", "interreflection: N bounces of light between the mesh's surfaces (0: direct only), or auto:\n"
              "until a pass adds less than the bake's own noise (at most 16) [default 0]", &bounces_);
  args.option("--albedo", "A|R,G,B|vertex", "the surfaces' diffuse albedo for interreflection: grey A, linear R,G,B (coloured\n"
              "bounces: RGB transfer), or the input's vertex colours (sRGB, decoded) [default 0.8]", &albedo_);
  args.option("--albedo-map", "PATH", "the albedo from a diffuse texture through the input's UVs (8-bit images are sRGB,\n"
              "decoded, 16-bit too; EXR/HDR linear): coloured bounces, RGB transfer", &albedo_map_);
  args.option("--bounce-rekey", "S", "adaptive refinement with bounces: refine on direct light to share S of the budget, bounce,\n"
              "then refine the rest keyed on the bounced light, when S of the budget is above the input's\n"
              "count (0: refine on direct light only) [default 0.5]", &bake.rekey_share, 0.0, 1.0);
  args.flag("--bounce-vertices-only", "interreflection: bounce at the vertices only, not also at the fit's samples before\n"
            "fitting again", &bounce_vertices_only_);
  args.choice("--bounce-cache", "interreflection: keep each ray's hit between passes (auto: while under 1 GiB)", &bake.bounce.cache,
              {BounceCache::Auto, BounceCache::On, BounceCache::Off}, bounce_cache_name);
  args.choice("--fit", "vertex values: traced at the vertex, averaged from surface samples, or the least-squares fit\n"
              "to them (Kavan et al. 2011)", &f.method, {FitMethod::Point, FitMethod::Average, FitMethod::LeastSquares}, fit_method_name);
  args.option("--alpha", "A|auto", "lsq: regulariser weight (0: the plain least-squares optimum), or auto: of 0, 0.01 and\n"
              "0.04 the one whose fit has the lowest error on the pilot's held-out samples (without a\n"
              "pilot, 0.04) [default auto]", &alpha_);
  args.choice("--regularizer", "lsq: penalise gradient jumps across edges, or gradients", &f.regularizer,
              {Regularizer::Edge, Regularizer::Gradient}, regularizer_name);
  args.choice("--mass", "lsq: exact mass matrix, or the samples' own", &f.mass, {MassMatrix::Analytic, MassMatrix::Sampled},
              mass_matrix_name);
  args.choice("--solver", "lsq: chosen per system (auto), conjugate gradients on the scaled system (cg) or with a\n"
              "multigrid preconditioner (multigrid; both need the analytic mass and fall back to CHOLMOD if\n"
              "they stall), or always a CHOLMOD Cholesky factorisation", &f.solver,
              {FitSolver::Auto, FitSolver::Cg, FitSolver::Multigrid, FitSolver::Cholmod}, fit_solver_name);
  args.option("--cg-tolerance", "T", "lsq: conjugate gradients stop at this residual relative to the right-hand side",
              &f.cg_tolerance, 1e-16, 1.0);
  args.flag("--no-control-variate", "lsq, analytic mass: estimate b as the paper does, without the point samples' control\n"
            "variate (for comparison; noisier)", &no_control_variate_);
  args.flag("--no-unshadowed-projection", "lsq, transfer: interpolate the unshadowed part t_u(n) from the vertices as\n"
            "point values do, instead of projecting it exactly (for comparison)", &no_unshadowed_projection_);
  args.flag("--no-noise-weighting", "lsq: keep the whole fit everywhere instead of weighing its correction against the point\n"
            "samples by their noise", &no_noise_weighting_);
  args.choice("--non-negative", "lsq: keep the fit from negative radiance under constant lights (the DC coefficient), also\n"
              "under narrow ones (the transfer function at 128 directions; costs accuracy), or not at all", &f.non_negative,
              {NonNegative::Off, NonNegative::Constant, NonNegative::Directions}, non_negative_name);
  args.option("--samples-per-triangle", "N", "fit: average surface samples per triangle (--refine auto: twice this, spread\n"
              "over the input's surface by area)", &s.per_triangle, 0.0, 1e6);
  args.option("--sample-density", "D", "fit: samples per unit area instead (world units)", &s.density, 0.0, 1e30);
  args.option("--min-samples", "M", "fit: samples every triangle gets at least", &s.min_per_triangle, size_t(0), size_t(1) << 20);
  args.option("--sample-rays", "R", "fit: rays per surface sample [default: the pilot chooses 4, 16 or 32 for the same sample\n"
              "rays (16 each without it); below the input's count (adaptive or auto), half of\n"
              "--rays]", &bake.sample_rays, 1, 1 << 20);
  args.choice("--sample-allocation", "fit: which faces get samples: only those where a pilot pass finds that interpolating\n"
              "the vertex values fails, or every face by area (the paper's)", &bake.allocation,
              {SampleAllocation::Pilot, SampleAllocation::Area}, sample_allocation_name);
  args.option("--pilot-samples", "N", "fit, pilot: pilot samples per triangle", &bake.pilot.per_triangle, 0.01, 1e3);
  args.option("--error", "E", "fit, pilot: trace more vertex rays until the error measured on the pilot's held-out samples\n"
              "(eval's percent) is at most E (without --rays, the first round's rays are chosen for E: 32\n"
              "to 256, from a pilot of the vertices); 0: off", &bake.target_error, 0.0, 1e6);
  args.option("--pilot-vertex-share", "S", "fit, pilot: share of the sample rays the pilot saved that go to the noisiest\n"
              "vertices instead", &bake.vertex_share, 0.0, 1e3);
  args.option("--pilot-rays", "R", "fit, pilot: rays per pilot sample", &bake.pilot.rays, 2, 1 << 20);
  args.option("--pilot-area-share", "A", "fit, pilot: share of a sampled face's density that follows its area alone (the rest\n"
              "follows its estimated interpolation error)", &bake.pilot.area_share, 0.0, 1.0);
  args.option("--pilot-first-share", "S", "fit, pilot: below 1, trace this share of the pilot first and the rest only on faces\n"
              "the first stage could not clear", &bake.pilot.first_share, 0.0, 1.0);
  args.option("--pilot-first-significance", "Z", "fit, pilot, two stages: standard errors a face's first-stage pool must exceed\n"
              "for the second stage to trace its other samples", &bake.pilot.first_significance, -1e6, 1e6);
  args.option("--pilot-rings", "N", "fit, pilot: each face pools the pilot samples within N vertex rings", &bake.pilot.rings, 1, 8);
  args.option("--pilot-significance", "Z", "fit, pilot: standard errors a ring's excess residual must exceed to get samples",
              &bake.pilot.significance, 0.0, 1e6);
  args.option("--pilot-screen", "Q", "fit, pilot: first trace up to 65,536 pilot samples; when the signal's variation inside\n"
              "the faces is below Q times the vertices' own noise there (a dense scan), stop: no fit samples,\n"
              "their rays go to the vertices; 0: off", &bake.pilot.screen_ratio, 0.0, 1e6);
}

void BakeCli::add_refinement(ArgParser& args) {
  args.choice("--refine", "refinement (auto: simplified where the transfer is smooth, then split where it varies)", &bake.refine,
              {Refinement::None, Refinement::Adaptive, Refinement::Uniform, Refinement::Auto}, refinement_name);
  args.option("--budget", "T", "adaptive, auto: output triangle count (required); adaptive below the input's simplifies",
              &bake.adaptive.budget, size_t(0), size_t(1) << 30);
  args.option("--surface-tolerance", "D", "adaptive below the input, auto: no collapse moves the surface by more than D times the "
              "bounding-box diagonal (adaptive relaxes it up to 8x where the budget needs it)",
              &bake.simplify.surface_tolerance, 1e-6, 0.04);
  args.option("--auto-share", "S", "auto: simplify to this share of min(budget, input) before refining", &bake.auto_share,
              1e-6, 1.0);
  args.option("--auto-cycles", "N", "auto: further cycles, each collapsing a share of the budget where the refined mesh is\n"
              "smoothest and refining back to it", &bake.auto_cycles, 0, 8);
  args.option("--auto-cycle-share", "S", "auto: the share of the budget each further cycle collapses", &bake.auto_cycle_share, 1e-6, 0.5);
  args.choice("--simplify-metric", "adaptive below the input: rank collapses by the transfer's change and the geometry, or the "
              "geometry alone", &bake.simplify.metric, {SimplifyMetric::Transfer, SimplifyMetric::Geometry}, simplify_metric_name);
  args.flag("--lock-corners", "adaptive below the input, auto: never collapse a vertex where three or more creases or seams\n"
            "meet (by default it may, along one of them, its other sides' render vertices moving with it)", &lock_corners_);
  args.option("--min-angle", "A", "adaptive below the input: no collapse makes a face with an angle below A degrees",
              &bake.simplify.min_angle_deg, 0.0, 59.0);
  args.option("--geometry-weight", "W", "adaptive below the input, transfer metric: weight of the quadric against the transfer's change",
              &bake.simplify.geometry_weight, 0.0, 1e12);
  args.option("--simplify-alpha", "A", "adaptive below the input: the fit's regulariser weight there (--alpha is the others')",
              &bake.simplified_alpha, 0.0, 1e12);
  args.choice("--estimate", "adaptive: edge error estimate", &bake.estimate,
              {EdgeEstimate::Relative, EdgeEstimate::Shadow, EdgeEstimate::Curvature, EdgeEstimate::Length, EdgeEstimate::Probe,
               EdgeEstimate::Root},
              estimate_name);
  args.option("--max-edge", "L", "adaptive: first split edges longer than L (0: off)", &bake.adaptive.max_edge, 0.0, 1e30);
  add_batch_option(args, bake.adaptive);
  args.option("--levels", "K", "uniform: 1→4 splits per face", &bake.uniform.levels, 1, 8);
  args.choice("--scheme", "uniform: linear keeps the surface; loop smooths it", &bake.uniform.scheme,
              {UniformScheme::Linear, UniformScheme::Loop}, uniform_scheme_name);
}

void BakeCli::add_basis(ArgParser& args) {
  args.option("--basis", "sh|sg:N", "the transfer's basis: SH of --order, or N spherical-Gaussian lobes (4 to 16; 9 and 12 are\n"
              "the usual; each vertex's own least-squares encoding, non-negative; docs/sh_convention.md) [default sh]", &basis_);
  args.flag("--sg-signed", "--basis sg: let lobe coefficients go negative (lower error; a narrow light can then shade negative)",
            &bake.sg_signed);
  args.when_given("--fit", [this] { fit_given_ = true; });
}

BakeOptions BakeCli::options() const {
  BakeOptions o = bake;
  if (!basis_.empty() && basis_ != "sh") {
    char* end = nullptr;
    const long n = basis_.rfind("sg:", 0) == 0 ? std::strtol(basis_.c_str() + 3, &end, 10) : 0;
    if (!end || end == basis_.c_str() + 3 || *end != '\0' || n < kMinSgLobes || n > kMaxSgAssetLobes)
      throw UsageError("--basis: expected sh or sg:N with N from " + std::to_string(kMinSgLobes) + " to " + std::to_string(kMaxSgAssetLobes) +
                       ", got '" + basis_ + "'");
    o.sg_lobes = static_cast<int>(n);
    if (!fit_given_) o.fit.method = FitMethod::Point;  // the lobes are each vertex's own encoding
  }
  if (o.sg_signed && o.sg_lobes == 0) throw UsageError("--sg-signed: only with --basis sg:N");
  if (bounces_ == "auto") {
    o.bounce.until_converged = true, o.bounce.bounces = 16;
  } else if (!bounces_.empty()) {
    char* end = nullptr;
    const long n = std::strtol(bounces_.c_str(), &end, 10);
    if (end != bounces_.c_str() + bounces_.size() || n < 0 || n > 64)
      throw UsageError("--bounces: expected 0 to 64 or auto, got '" + bounces_ + "'");
    o.bounce.bounces = static_cast<int>(n);
  }
  if (!albedo_.empty() && !albedo_map_.empty()) throw UsageError("--albedo and --albedo-map: give one");
  if (!albedo_.empty()) {
    try {
      const AlbedoSpec a = parse_albedo(albedo_);
      if (a.coloured()) o.albedo_colour = a;
      else o.bounce.albedo = a.constant.x();
    } catch (const InputError& e) {
      throw UsageError(std::string("--albedo: ") + e.what());
    }
  }
  if (!albedo_map_.empty()) {
    o.albedo_colour.source = AlbedoSource::Map, o.albedo_colour.map = albedo_map_;
    o.albedo_colour.image = std::make_shared<const Image>(cli_read_image(albedo_map_));
  }
  if (alpha_ != "auto") {
    char* end = nullptr;
    const double a = std::strtod(alpha_.c_str(), &end);
    if (alpha_.empty() || end != alpha_.c_str() + alpha_.size() || !(a >= 0) || !std::isfinite(a))
      throw UsageError("--alpha: expected a non-negative number or auto, got '" + alpha_ + "'");
    o.fit.alpha = a, o.alpha_auto = false;
  }
  if (order_ == "auto") {
    o.order_auto = true;
  } else if (!order_.empty()) {
    char* end = nullptr;
    const long n = std::strtol(order_.c_str(), &end, 10);
    if (end != order_.c_str() + order_.size() || n < 1 || n > kMaxShOrder)
      throw UsageError("--order: expected 1 to " + std::to_string(kMaxShOrder) + " or auto, got '" + order_ + "'");
    o.transfer.order = static_cast<int>(n);
  }
  if (!order_lights_.empty()) {
    if (!o.order_auto) throw UsageError("--order-light: only with --order auto");
    const ShLight light = parse_lights(order_lights_, o.order_choice.max_order, "--order-light");
    o.order_choice.band_power.assign(static_cast<size_t>(o.order_choice.max_order), 0.0);
    for (int l = 0; l < o.order_choice.max_order; ++l)
      for (int k = l * l; k < (l + 1) * (l + 1); ++k)
        o.order_choice.band_power[static_cast<size_t>(l)] += light.coeffs.row(k).squaredNorm() / 3;  // the channels' mean
  }
  if (rays_fixed_ > 0) o.transfer.rays = rays_fixed_, o.round_rays = 0;
  if (sample_rays_given_) o.sample_rays_auto = false;
  o.rays_auto = o.target_error > 0 && !rays_given_ && rays_fixed_ == 0 && o.round_rays == 0;
  if (o.round_rays % 2 != 0) throw UsageError("--first-rays: expected an even count, got " + std::to_string(o.round_rays));
  o.bounce.fit_samples = !bounce_vertices_only_;
  o.fit.control_variate = !no_control_variate_;
  o.fit.weigh_by_noise = !no_noise_weighting_;
  o.simplify.collapse_corners = !lock_corners_;
  o.unshadowed_projection = !no_unshadowed_projection_;
  o.source = input;
  if ((o.refine == Refinement::Adaptive || o.refine == Refinement::Auto) && o.adaptive.budget == 0)
    throw UsageError(std::string("--budget: required with --refine ") + refinement_name(o.refine));
  try {
    check_bake_options(o);
  } catch (const InputError& e) {
    throw UsageError(e.what());
  }
  return o;
}

StageProgress::StageProgress() : enabled_(stderr_is_terminal()) {}
StageProgress::~StageProgress() { finish(); }
void StageProgress::finish() {
  if (current_) current_->finish();
  current_.reset();
}
BakeProgress StageProgress::callbacks() {
  BakeProgress p;
  p.stage = [this](const char* stage, size_t total) {
    finish();
    current_ = std::make_unique<Progress>(stage, total, enabled_);
  };
  p.add = [this](size_t n) {
    if (current_) current_->add(n);
  };
  return p;
}

}  // namespace prtsub
