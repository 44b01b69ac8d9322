// The whole bake as one call: mesh → (uniform refinement) → transfer at the vertices →
// (adaptive refinement) → (surface samples and fit) → the asset's vertex values.
//
//   prtsub::Mesh mesh = prtsub::load_mesh("bunny.ply");      // or build_mesh(raw) in memory
//   prtsub::BakeOptions o;
//   o.refine = prtsub::Refinement::Adaptive;
//   o.adaptive.budget = 100000;
//   prtsub::BakeResult r = prtsub::bake(mesh, o);
//   prtsub::write_asset("bunny_prt.ply", r.mesh, r.transfer, r.metadata);
//
// The library prints nothing: progress arrives through BakeProgress, warnings in the result.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "prtsub/prt/asset.h"
#include "prtsub/prt/error_estimate.h"
#include "prtsub/prt/fit.h"
#include "prtsub/prt/interreflection.h"
#include "prtsub/prt/order_choice.h"
#include "prtsub/prt/refine_signal.h"
#include "prtsub/prt/sample_plan.h"
#include "prtsub/prt/vertex_top_up.h"
#include "prtsub/subdiv/refine.h"
#include "prtsub/subdiv/simplify.h"
#include "prtsub/subdiv/uniform.h"

namespace prtsub {

enum class Refinement {
  None,      //!< the input's own triangles
  //! to exactly `adaptive.budget` triangles where the transfer changes: split above the
  //! input's count, simplified (collapses where it does not change) below it
  Adaptive,
  Uniform,   //!< OpenSubdiv 1→4 splits, `uniform.levels` times: the baseline
  //! both ways, to exactly `adaptive.budget` triangles from any input: simplified first (to
  //! `auto_share` of the smaller of the budget and the input's count) where the transfer is
  //! smooth, then split where it varies; new vertices are traced at their closest points on the
  //! input, and the fit samples the input's surface
  Auto,
};
Refinement parse_refinement(const std::string& name);  //!< none, adaptive, uniform, auto \throw InputError
const char* refinement_name(Refinement r);

struct BakeOptions {
  //! Order, rays, seed and threads of the vertices' transfer. AO bakes force order 1; the
  //! samples' seed and the fit's threads derive from these.
  TransferOptions transfer;
  //! Per-vertex early stop (early_stop_vertices), off when 0: every input vertex first traces this
  //! many rays, then doubles them round by round up to transfer.rays while its estimated noise
  //! (the square root of its variance), or its faces', is above stop_noise_percent of
  //! ||t_unshadowed||, eval's unit. At transfer.rays ≤ round_rays every vertex traces
  //! transfer.rays. Refinement's new vertices and the fit's samples trace fixed counts.
  int round_rays = 0;
  double stop_noise_percent = 0.5;
  //! --order auto: transfer.order is chosen from a pilot of the vertices before anything else is
  //! traced (order_choice.h); transfer.order is then ignored. Transfer assets only.
  bool order_auto = false;
  OrderChoiceOptions order_choice;
  AssetSignal signal = AssetSignal::Transfer;  //!< Ao: order-1 transfer, written as ambient occlusion
  //! --basis sg:N: when > 0, transfer as this many spherical-Gaussian lobes (sg_basis.h; 4 to
  //! kMaxSgAssetLobes) in place of SH of transfer.order. Each vertex's lobes are encoded from its
  //! transfer.rays rays by sg_transfer (the progressive least-squares encoder, transfer.progressive),
  //! non-negative unless sg_signed. Refinement (none, uniform, adaptive above the input's count)
  //! keys on the lobes' L² distance on the sphere, as it does on SH's. The values are the vertices'
  //! own (fit point): the fit, bounces, a coloured albedo, --error, --order auto, early stop and
  //! shards are SH's alone (check_bake_options says so).
  int sg_lobes = 0;
  bool sg_signed = false;
  Refinement refine = Refinement::None;
  RefineOptions adaptive;                      //!< Adaptive: budget (required), batch, max_edge
  //! Adaptive with a budget below the input's: the metric and the guards (its budget and value
  //! scale come from `adaptive` and the SH order)
  SimplifyOptions simplify;
  //! the fit's regulariser weight on a simplified mesh (fit.alpha is the refined and unrefined
  //! meshes'): a coarse face spans real curvature of the transfer, which a strong edge regulariser
  //! flattens; 0.002 measured best at 10% on bunny, chinese_dragon and mori_knob (BENCHMARKS.md)
  double simplified_alpha = 0.002;
  //! Auto: the share of min(budget, input triangles) simplification goes down to before
  //! refinement spends the rest where the transfer varies; 0.8 measured best on sibenik of
  //! 0.5-0.95 (BENCHMARKS.md, "Both ways")
  double auto_share = 0.8;
  //! Auto: further cycles after the first, each collapsing auto_cycle_share of the budget where
  //! the refined mesh is smoothest (the ranking now sees refinement's traced vertices) and
  //! refining back to the budget on fresh keys; one cut the error by 0-6% on eight scenes
  //! (BENCHMARKS.md)
  int auto_cycles = 1;
  //! Auto: the share of the budget each further cycle collapses, in (0, 0.5]. Smaller cycles move
  //! fewer triangles each: four of 0.03 beat one of 0.1 by 2-3% on four of eight scenes, tied on
  //! two, and lost 1.6% on mori_knob and 5% on conference (BENCHMARKS.md, "Cycles of another size")
  double auto_cycle_share = 0.1;
  EdgeEstimate estimate = EdgeEstimate::Root;  //!< Adaptive: the edge error estimate
  UniformOptions uniform;                      //!< Uniform: levels and scheme
  FitOptions fit;                              //!< vertex values: point samples, or fitted to surface samples
  //! LeastSquares with the pilot: fit.alpha is chosen among alpha_choices (ascending), moving to
  //! the next only while it lowers the error on the pilot's held-out samples by more than twice the
  //! standard error of the paired difference (the regulariser's right strength
  //! depends on how noisy the samples are against what they correct: none on most shared scenes,
  //! 0.01 on conference; BENCHMARKS.md). Off, or without a hold-out: fit.alpha as given.
  bool alpha_auto = true;
  std::array<double, 3> alpha_choices = {0, 0.01, 0.04};
  SampleOptions samples;                       //!< how many samples the fit gets (its seed derives from transfer.seed)
  //! which faces get them: Pilot spends them only where interpolation fails (needs sample_rays ≥ 2)
  SampleAllocation allocation = SampleAllocation::Pilot;
  PilotOptions pilot;
  //! Pilot: the share of the sample rays the pilot saved (against sampling every face) that goes
  //! to more rays at the noisiest vertices instead (top_up_vertices), at most as many as the vertices
  //! traced before it (so --rays sets the cost); 0 keeps them unspent
  double vertex_share = 0.5;
  //! --error: when > 0 (percent, eval's unit), trace more vertex rays, or give the fit more samples
  //! where interpolation is what is left, until the error measured on the pilot's held-out
  //! samples is at most this (needs Pilot allocation)
  double target_error = 0;
  //! With target_error: the first round's rays are chosen instead of transfer.rays, the least of
  //! 32, 64, 128 and 256 whose noise a pilot of vertices predicts within target_error/√2
  //! (choose_first_rays), so that a loose target costs a cheap bake (later rounds add what the
  //! hold-out finds missing). The CLI sets it when --error is given without --rays.
  bool rays_auto = false;
  //! With target_error and bounces: paths per held-out sample for its bounced light
  //! (bounced_holdout), which the target then holds for
  int target_paths = 128;
  //! ... on a quarter of this many of the held-out samples first, then, when the error is within
  //! three standard errors of the target, on this many (holdout_subset)
  size_t target_paths_points = 8192;
  //! rays per surface sample; with the pilot and sample_rays_auto, the budget of sample rays this
  //! count sets (samples.per_triangle · sample_rays per sampled face) is instead split among
  //! sample_ray_choices as the pilot's measurements say (choose_sample_rays: 4 where shadows cross
  //! large faces, 32 on smooth scans, else this count). Below the input's count
  //! (simplified, or both ways there), sample_rays_auto gives the fit's samples on the source half
  //! of transfer.rays each, at least this count (docs/simplification.md)
  int sample_rays = 16;
  bool sample_rays_auto = true;
  std::array<int, 3> sample_ray_choices = {4, 16, 32};
  //! Transfer with the least-squares fit: the curvature of the unshadowed part t_u(n) inside the
  //! faces, known in closed form, is projected exactly onto the mesh instead of left to
  //! interpolation, and the pilot looks for samples' work only in what is left (FitOptions::
  //! unshadowed_order, PilotOptions::exact_unshadowed; docs/fit.md). No rays: on dense scans most
  //! of what interpolation misses is that curvature.
  bool unshadowed_projection = true;
  //! Interreflection (transfer only): bounces, albedo, the cache; its rays, seed and threads are
  //! the transfer's. Applied to the asset's values after the fit (refinement and the fit see
  //! direct transfer).
  BounceOptions bounce;
  //! A coloured albedo (R,G,B, the input's vertex colours or a map through its UVs), in place of
  //! bounce.albedo's grey: the bounces then give RGB transfer (#V by 3·N²), and the asset records
  //! the albedo at every vertex. A grey constant (the default) leaves bounce.albedo in charge.
  AlbedoSpec albedo_colour;
  //! Adaptive refinement with bounces: when in (0, 1), refine on direct transfer to this share of
  //! the budget, bounce there, and refine the rest keyed on the bounced light (new vertices: their
  //! traced direct transfer plus their edge's midpoint bounced light); only when that share is
  //! above the input's count (else it refines on direct transfer alone, measured no worse and
  //! faster: BENCHMARKS.md). 0: refine on direct transfer only, and bounce after.
  double rekey_share = 0.5;
  std::string source;  //!< recorded in the asset's metadata as "source" (a path, or any name)
  //! Stop after refinement (or simplification): the mesh with its point-sampled vertex transfer,
  //! no samples, fit, error target or bounces. Such an asset is a mesh file that later bakes
  //! (sharded ones among them, which need a fixed mesh) take as input.
  bool refine_only = false;
};

//! Told when a stage with `total` work items starts, then of items as they finish (from
//! worker threads). Either part may be empty.
struct BakeProgress {
  std::function<void(const char* stage, size_t total)> stage;
  ProgressFn add;
};

//! Where the fit's samples and their transfer come from, kept so that several fits can share them.
struct FitData {
  SampleAllocation allocation = SampleAllocation::Area;  //!< what ran (Pilot falls back to Area with 1 ray)
  SamplePlan plan;       //!< Pilot: the pilot's findings (its rays are included in `rays`)
  SurfaceSamples samples;
  FaceMoments moments;  //!< the samples' transfer, reduced face by face as it is traced
  int sample_rays = 0;  //!< rays per sample they were traced with (the pilot's choice, or BakeOptions::sample_rays)
  uint64_t rays = 0;
  double seconds = 0;
};

struct BakeResult {
  Mesh mesh;             //!< the output mesh
  RowMatrixXd transfer;  //!< #V by N²: the asset's values (order-1 transfer for AO); #V by 3·N² when a coloured albedo bounced
  RowMatrixXd point;     //!< #V by N²: the point-sampled values (equal to transfer when fit is point)
  RowMatrixX3d albedo;   //!< #V by 3: the albedo at each vertex when it is coloured, else no rows
  //! Auto: per vertex, 1 where refinement made it (traced at its closest point on the input,
  //! not where it stands: the second round of vertex rays leaves it out)
  std::vector<char> refined_vertex;
  int auto_cycles = 0;                //!< Auto: further cycles run (BakeOptions::auto_cycles)
  size_t auto_cycle_collapses = 0;    //!< ... and the collapses they made (in simplify.collapses too)
  size_t rekeyed_at = 0;  //!< faces when refinement turned to keys on bounced light (0: it did not)
  std::vector<double> point_variance;  //!< #V: each point value's estimated variance (summed over N²)
  //! #V by N²: each point value's two independent halves' difference t_A − t_B, carried through
  //! its later rounds so that point_variance stays that of one lattice pair (NaN where unknown:
  //! after refinement or simplification, which make new vertices)
  RowMatrixXd point_halves;
  RefineStats refine;    //!< adaptive refinement's counts and times
  bool simplified = false;     //!< the budget was below the input's: simplified, not refined
  SimplifyStats simplify;      //!< simplification's counts and times
  FitData fit_data;      //!< the samples (empty when fit is point)
  TopUpStats top_up;     //!< the second round of vertex rays (Pilot allocation)
  EarlyStopStats early_stop;  //!< the vertices' later rounds (round_rays)
  //! Pilot allocation: the asset's error measured on the pilot's held-out samples (what eval
  //! would report; all 0 otherwise)
  ErrorEstimate predicted;
  std::vector<double> vertex_rays;  //!< #V: rays traced at each vertex, all rounds
  uint64_t target_rays = 0;         //!< --error: the vertex rays its rounds added
  int target_rounds = 0;            //!< --error: rounds of vertex rays
  int target_sample_rounds = 0;     //!< --error: rounds of more samples
  size_t target_samples = 0;        //!< --error: the samples they added ...
  uint64_t target_sample_rays = 0;  //!< ... and their rays
  FirstRoundChoice first_round;     //!< rays_auto: the first round's rays and why (rays 0 otherwise)
  //! --error with bounces: `predicted` is the bounced asset's; this is its direct light's, before
  //! the bounces (all 0 without them)
  ErrorEstimate predicted_direct;
  int bounce_rays = 0;              //!< rays per vertex of each bounce pass, as run last (0: no bounces)
  int bounce_rays_chosen = 0;       //!< ... as first run: with --error, fewer than the direct light's where the target leaves room
  int target_bounce_rounds = 0;     //!< --error with bounces: bounce passes run again with more rays ...
  int target_direct_rounds = 0;     //!< ... or after more direct vertex rays
  //! --error: rays spent measuring: the held-out samples traced again for a sharper estimate, and
  //! with bounces the held-out samples' paths and the passes' noise
  uint64_t target_holdout_rays = 0;
  //! a simplified or both-ways asset: rays that traced its hold-out (on the source) again, where
  //! the prediction's standard error was above a quarter of it
  uint64_t holdout_sharpen_rays = 0;
  FitStats fit;
  double alpha = 0;  //!< the fit's regulariser weight as used (chosen, with alpha_auto)
  //! alpha_auto: each candidate α and the held-out error of its fit, in percent (empty otherwise)
  std::vector<std::pair<double, double>> alpha_trials;
  BounceStats bounce;    //!< interreflection's passes (none when bounce.bounces is 0)
  OrderChoice order;     //!< --order auto: the order chosen and why (order 0 otherwise)
  size_t clamped = 0;    //!< AO: values clamped into [0, 1] after the fit
  uint64_t rays = 0;     //!< every transfer ray traced
  double seconds_scene = 0, seconds_transfer = 0, seconds_refine = 0, seconds_samples = 0, seconds_top_up = 0, seconds_target = 0, seconds_fit = 0, seconds_bounce = 0,
         seconds_total = 0;
  std::vector<std::string> warnings;
  Metadata metadata;     //!< what the asset records
};

//! The least-squares fit as the bake runs it (options.fit, with fit_prior's correction), and with
//! options.alpha_auto and a pilot's hold-out in `data`, at the α of alpha_choices (ascending)
//! reached by moving to the next only while its fit is better on the held-out samples by more than
//! twice the standard error of the paired difference (holdout_difference). For fit methods other than LeastSquares, the plain
//! fit_vertex_values.
//! \param prior #V by K, the point values; prior_variance #V (or empty: no noise weighting)
//! \param alpha receives the α used; trials each candidate's held-out error (percent), if asked
RowMatrixXd fit_bake_values(const Mesh& mesh, const FitData& data, const RowMatrixXd& prior, const std::vector<double>& prior_variance,
                            const BakeOptions& options, FitStats* stats = nullptr, double* alpha = nullptr,
                            std::vector<std::pair<double, double>>* trials = nullptr);

//! Runs the pipeline on `mesh` (which it copies; refinement changes the copy).
//! \throw InputError for bad options or a mesh refinement cannot take, EmbreeError, SolverError
BakeResult bake(const Mesh& mesh, const BakeOptions& options, const BakeProgress& progress = {});

//! The options bake() actually runs with: AO forces order 1, the samples' seed derives from
//! transfer.seed and the fit's threads are the transfer's.
BakeOptions resolve_bake_options(const BakeOptions& options);

//! Checks options before any work. \throw InputError naming the value at fault
void check_bake_options(const BakeOptions& options);

//! Whether the vertices stop early: round_rays set and below transfer.rays (else every vertex
//! traces transfer.rays).
bool early_stop_on(const BakeOptions& options);

//! A sharded bake (transfer.log set) needs a fixed mesh: adaptive and auto refinement trace
//! inside their one queue. \throw InputError saying so when `options` would refine adaptively
void check_fixed_mesh(const BakeOptions& options);

//! The fit's samples on `mesh` and their transfer (stages "pilot" and "samples").
//! \param prior, prior_variance the vertices' point values and their variances: the pilot
//!        compares its samples with them (Area allocation ignores them; may then be null)
FitData sample_signal(const Mesh& mesh, const RayScene& scene, const BakeOptions& options, const RowMatrixXd* prior,
                      const std::vector<double>* prior_variance, const BakeProgress& progress = {});

//! The samples' transfer, reduced to the fit's face moments and their variances as it is traced;
//! the same for any thread count.
FaceMoments trace_face_moments(const Mesh& mesh, const RayScene& scene, const SurfaceSamples& samples,
                               const TransferOptions& options, TransferStats* stats = nullptr, const ProgressFn& progress = {});

}  // namespace prtsub
