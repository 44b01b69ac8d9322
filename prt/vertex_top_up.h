// More rays for the vertices whose transfer is noisiest: a second round of vertex tracing that
// spends a ray budget where it lowers the summed variance most.
#pragma once

#include <functional>
#include <vector>

#include "prtsub/prt/transfer.h"
#include "prtsub/subdiv/mesh.h"

namespace prtsub {

struct TopUpStats {
  size_t vertices = 0;  //!< vertices that got more rays
  uint64_t rays = 0;
  double seconds = 0;
  double variance_before = 0, variance_after = 0;  //!< summed over the vertices (estimated)
  std::vector<size_t> histogram;  //!< [j + 1]: vertices doubled j times; [0]: vertices given none
};

//! Which vertices get how many more rays: level[i] = j doubles vertex i's rays j times (R_i·(2^j − 1)
//! more), -1 for none.
struct TopUpPlan {
  std::vector<int> level;
  size_t vertices = 0;  //!< with a level
  uint64_t rays = 0;    //!< that the plan will trace
};
//! The allocation alone (see top_up_vertices), from each vertex's variance after rays[i] rays,
//! each vertex to at most max_rays in all.
//! \param weight #V or empty: how much each vertex's variance counts (the area it interpolates
//!        over, for an error measured over the surface); empty counts them equally
TopUpPlan plan_top_up(const std::vector<double>& variance, const std::vector<double>& rays, uint64_t budget,
                      const std::vector<double>& weight, double max_rays);

//! The cheapest plan of the same water-filling (from `planning`, each vertex's variance to plan
//! by) whose planned_variance(plan, variance, rays, weight) is at most `target`; the plan with
//! every vertex at its most if none is.
TopUpPlan plan_top_up_to_variance(const std::vector<double>& planning, const std::vector<double>& rays, double target,
                                  const std::vector<double>& variance, const std::vector<double>& weight, double max_rays);

//! Σ_i weight_i·variance_i as it will be after the plan (each variance falling as 1/rays).
double planned_variance(const TopUpPlan& plan, const std::vector<double>& variance, const std::vector<double>& rays,
                        const std::vector<double>& weight);

//! How many rings smoothed_variance averages over by default: measured on the default bake (eval
//! --rays 2048), armadillo AO 0.533% at one ring, 0.521% at three, 0.516% at six; armadillo
//! transfer 1.146%, 1.134%, 1.132%; bunny transfer and AO a little better, the coarse scenes the same.
constexpr int kVarianceRings = 6;

//! Each vertex's per-ray variance averaged over the faces around it (each face the mean of its
//! corners', weighed by its area), at the vertex's own ray count: what to plan with. One
//! vertex's estimate compares two half-estimates, a chi-square of one degree of freedom per
//! coefficient (AO has one coefficient): too noisy to allocate by alone, while the variance
//! itself varies smoothly over the surface. `rings` repeats the averaging (each time over the
//! last one's values), reaching that many rings of faces; each keeps the area-weighted total.
//! Vertices with an unknown variance keep theirs and spread nothing. \throw InputError for rings < 1
std::vector<double> smoothed_variance(const Mesh& mesh, const std::vector<double>& variance, const std::vector<double>& rays,
                                      int rings = kVarianceRings);

//! A third of the area of the faces around each vertex: the weights for a surface error.
std::vector<double> vertex_areas(const Mesh& mesh);

//! A pilot of vertices: every ⌈V / count⌉-th render vertex (a systematic subset, spread over the
//! mesh as its vertices are), with its position, normal and ray-offset direction.
struct PilotVertices {
  std::vector<size_t> index;
  RowMatrixX3d points, normals, offsets;
};
PilotVertices pilot_vertices(const Mesh& mesh, size_t count);

//! The first round's rays an error target asks for (--error without --rays).
struct FirstRoundChoice {
  int rays = 0;                      //!< chosen: the least of the choices whose noise is within the target
  size_t points = 0;                 //!< pilot vertices traced
  uint64_t pilot_rays = 0;           //!< their rays (spent on the estimate alone)
  std::vector<double> noise_percent;  //!< per choice: the noise it would leave, in the target's unit
  double decay = 0;                  //!< the noise's measured exponent, R^-decay (0.5 for independent rays)
};

//! Traces a systematic pilot of at most `points` vertices (every ⌈V/points⌉-th) at pilot_rays/2
//! and at pilot_rays (seed mixed from options.seed: independent of every later ray); from their
//! variances (the estimator's two halves) estimates the surface noise Σ w_i σ_i²/2A at both counts
//! (w_i a third of the area around vertex i), hence its decay exponent (the lattice's error falls
//! faster than 1/√R), and picks the least of `choices` (ascending) whose noise at after·R rays is
//! at most `target_noise` (in the unit `unit` of values: ‖t_unshadowed‖/100 for percent), or the
//! largest. `after`: how many times the first round's rays the vertices will have traced when the
//! error is measured (2 with the pilot's second round of vertex rays).
FirstRoundChoice choose_first_rays(const Mesh& mesh, const RayScene& scene, const TransferOptions& options, double target_noise,
                                   double unit, const std::vector<int>& choices, double after = 1, size_t points = 2000,
                                   int pilot_rays = 128);

//! Traces a plan's rays and merges them into `values`, `variance` and `rays` (each vertex's ray
//! count so far, the weight of what it had). `options` are the first round's (seed, stream
//! offset, and rays = its count): each vertex's lattice is continued from where it stopped. An
//! odd first round cannot be doubled; then each round is an independent lattice of its own seed.
//! With `halves` (#V by K, each vertex's t_A − t_B from shadowed_transfer's half_difference, NaN
//! where unknown), the halves' differences are merged as the values are and a vertex's merged
//! variance is ‖t_A − t_B‖²/4: that of the one lattice pair its rounds make together (both
//! counts even). Without them, or where a row is unknown, the variance is merged as if the
//! rounds were independent: an upper estimate, 2.09 times the true squared error on the unit
//! test's scene, since a continued lattice fills its first round's gaps.
TopUpStats apply_top_up(const Mesh& mesh, const RayScene& scene, const TransferOptions& options, const TopUpPlan& plan,
                        RowMatrixXd& values, std::vector<double>& variance, std::vector<double>& rays,
                        const ProgressFn& progress = {}, RowMatrixXd* halves = nullptr,
                        std::vector<double>* independent = nullptr);
//! (`independent`, if given, #V: also merged as if the rounds were independent, whatever `halves` says.)

struct EarlyStopStats {
  size_t rounds = 0;  //!< after the first
  uint64_t rays = 0;  //!< the later rounds'
  double seconds = 0;
  //! [j]: vertices that stopped at the first round's count times 2^j
  std::vector<size_t> histogram;
};

//! How many doubling rounds fit between a first round of first_rays and max_rays.
int early_stop_rounds(int first_rays, int max_rays);

//! Per-vertex early stop, after a first round of `first.rays` rays at every render vertex of
//! `mesh` (values, variance and rays hold it). Round by round, a vertex doubles its rays
//! (continuing its lattice, within `max_rays`) while v·w/w̄ > stop_variance·R/max_rays: v its
//! variance after R rays, the larger of its own estimate and the faces' around it
//! (smoothed_variance), w/w̄ its area against the mean. That stops each vertex where the
//! variance a doubling removes (v/2) is worth less than the rays it costs (R), at one price for
//! the whole surface: Neyman's allocation, R ∝ σ√w, reached by stopping instead of planning. A
//! vertex of mean area stops at max_rays with variance stop_variance, with less where it gets
//! there earlier. A vertex whose first round is exact, fully open or fully enclosed (variance 0),
//! stops there unless a face around it saw otherwise. Ends when no vertex doubles, or after
//! early_stop_rounds(first.rays, max_rays) rounds.
//! `between_rounds`, if set, runs once per round that could run (early_stop_rounds), before it
//! or at the end (a sharded bake's barrier: its phases are counted before it traces). Does not
//! depend on threads.
//! `halves`, if given, as for apply_top_up: the variances left in `variance` are then the merged
//! lattices' own. The rule still reads the rounds merged as if independent, an upper estimate:
//! read with the lattices' own, a vertex whose halves agreed by chance stops on its luck (tried:
//! on the unit test's scene early stop then lost to a fixed count at the same rays).
EarlyStopStats early_stop_vertices(const Mesh& mesh, const RayScene& scene, const TransferOptions& first, int max_rays, double stop_variance,
                                   RowMatrixXd& values, std::vector<double>& variance, std::vector<double>& rays,
                                   const std::function<void()>& between_rounds = {}, const ProgressFn& progress = {},
                                   RowMatrixXd* halves = nullptr);

//! Traces up to `budget` more rays from the render vertices of `mesh` and merges them into
//! `values` (#V by K) and `variance` (#V, as shadowed_transfer estimates it), each vertex
//! weighted by its ray count. The first round traced `rays_done` rays at every vertex. The extra
//! rays minimise the summed variance, each vertex's weighted by the area around it (the surface
//! error eval measures), for the budget (water-filling on each vertex's per-ray standard
//! deviation, smoothed over its faces), each total rounded to rays_done·2^j and at most 16×
//! `rays_done`; an open vertex (variance 0: the estimator is exact there) gets none.
//! `options` gives order, seed and threads; the result does not depend on threads.
//! \throw InputError for shapes that do not match the mesh
TopUpStats top_up_vertices(const Mesh& mesh, const RayScene& scene, const TransferOptions& options, int rays_done,
                           uint64_t budget, RowMatrixXd& values, std::vector<double>& variance, const ProgressFn& progress = {});

}  // namespace prtsub
