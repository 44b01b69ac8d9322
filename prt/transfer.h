// Shadowed diffuse SH transfer at surface points, traced with Embree.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "prtsub/prt/progressive_encoder.h"
#include "prtsub/prt/ray_scene.h"

namespace prtsub {

class TraceLog;

//! How a point's rays become its N² coefficients (docs/transfer.md compares them).
enum class TransferEstimator {
  //! "cv" (the default): cosine-weighted lattice directions, the closed-form unshadowed transfer
  //! as a control variate chosen by the other half's visible share.
  ControlVariate,
  //! "mc": plain Monte Carlo projection, (π/R) Σ V_k y(ω_k) over independent cosine-weighted
  //! directions. The textbook baseline.
  MonteCarlo,
  //! "pls": the progressive least-squares encoder (progressive_encoder.h) fed V·max(n·ω, 0) on a
  //! uniform sphere: the lattice's directions on the hemisphere, each with its mirror image below
  //! the horizon (value 0, no ray), in a random order per point.
  Progressive,
  //! "pls-cv": the same encoder fed only the blocked part, (1 − V)·max(n·ω, 0), subtracted from
  //! the closed-form unshadowed transfer: exact where nothing is blocked.
  ProgressiveBlocked,
};

//! "cv", "mc", "pls", "pls-cv".
const char* estimator_name(TransferEstimator e);
//! \throw InputError naming the accepted names
TransferEstimator estimator_from_name(const std::string& name);

struct TransferOptions {
  int order = 4;       //!< SH order N (N² coefficients), 1..10
  int rays = 256;      //!< rays per point
  uint64_t seed = 0;   //!< the result is a function of (seed, point index), not of threads
  TransferEstimator estimator = TransferEstimator::ControlVariate;
  //! The encoder's options for the two progressive estimators (non_negative is refused: SH
  //! coefficients are signed).
  ProgressiveOptions progressive;
  int threads = 0;     //!< 0: every core
  //! Point i draws its directions from stream stream_offset + i: give refinement's new
  //! vertices their render-vertex index, so their rays do not depend on batching.
  uint64_t stream_offset = 0;
  //! If set (#P entries), point i's stream instead: a later round at some of the vertices gives
  //! each its own vertex's stream. Not owned; must outlive the call.
  const std::vector<uint64_t>* streams = nullptr;
  //! A later round of the same points (same seed and streams): their first round traced
  //! `first_round_rays` (even) and earlier rounds brought each to `first_ray` =
  //! first_round_rays·2^j; this one traces the next `rays`, to first_round_rays·2^(j+d). Each
  //! point's directions continue its lattice (each doubling contains the lattice before), so the
  //! rounds merged by ray count are the estimate of all those rays traced at once, and as
  //! stratified. first_round_rays = 0: a first round, of any count.
  uint32_t first_ray = 0;
  int first_round_rays = 0;
  //! A sharded bake's record (trace_log.h): calls are replayed from it, or only a slice of their
  //! points is traced into it. Not owned; null for an ordinary call.
  TraceLog* log = nullptr;
};

//! Called from worker threads with the number of points just finished.
using ProgressFn = std::function<void(size_t points_done)>;

struct TransferStats {
  uint64_t rays = 0;
  double seconds = 0;
};

//! t_i(p) = ∫ V(p,ω) max(n·ω,0) y_i(ω) dω at each point.
//! \param points #P by 3 world positions on the surface of `scene`
//! \param normals #P by 3 unit shading normals
//! \param offsets #P by 3 unit directions to move ray origins off the surface (default: the
//!        normals); see vertex_offset_directions
//! \param variance if given, receives #P estimates of each result's variance, summed over its
//!        N² values, from the disagreement of the estimator's two independent halves (infinite
//!        with a single ray); an unoccluded point's is 0
//! \param half_difference if given, receives #P by N²: each point's two independent halves'
//!        estimates, t_A − t_B (NaN with a single ray). Later rounds of the same points continue
//!        each half's own lattice, so differences merged by ray count as the values are stay those
//!        of one lattice pair: with even counts, the merged estimate's variance is ‖t_A − t_B‖²/4,
//!        where merging the rounds' variances as if independent overstates it (vertex_top_up.h).
//! \return #P by N² row-major transfer
//! \throw InputError for an order or ray count out of range, EmbreeError on Embree failure
RowMatrixXd shadowed_transfer(const RayScene& scene, const RowMatrixX3d& points,
                              const RowMatrixX3d& normals, const TransferOptions& options,
                              TransferStats* stats = nullptr, const ProgressFn& progress = {},
                              const RowMatrixX3d* offsets = nullptr, std::vector<double>* variance = nullptr,
                              RowMatrixXd* half_difference = nullptr);

//! Called from worker threads with one group's transfer: `rows` rows of N² values, row-major,
//! and each row's estimated variance (summed over its values; see shadowed_transfer).
using GroupFn = std::function<void(size_t group, const double* values, const double* variance, size_t rows)>;

//! The same transfer, handed over group by group instead of stored: group g is points
//! group_begin[g] .. group_begin[g+1]-1, and consume sees each group once, from some worker.
//! For reductions (the fit's per-face moments) that need not keep every point's result. One
//! thread traces a whole group: keep groups small (tens of points) or the cores go idle.
//! \throw InputError unless group_begin runs from 0 to #P without decreasing
void shadowed_transfer_groups(const RayScene& scene, const RowMatrixX3d& points, const RowMatrixX3d& normals,
                              const std::vector<size_t>& group_begin, const TransferOptions& options,
                              const GroupFn& consume, TransferStats* stats = nullptr, const ProgressFn& progress = {},
                              const RowMatrixX3d* offsets = nullptr);

struct SgBasis;

//! Transfer in spherical-Gaussian lobes (sg_basis.h): T(ω) = V(ω) max(n·ω, 0) ≈ Σ_k c_k G_k(ω) at
//! each point, the c_k fitted to `options.rays` rays by the progressive least-squares encoder
//! (`options.progressive`; non_negative keeps every c_k ≥ 0, so no light can come out negative),
//! with pls's directions: the hemisphere's lattice, each ray's mirror below the horizon a free
//! zero. Relit by radiance = albedo/π · Σ_k c_k L_k (sg_light). A single round, not sharded; the
//! same for any thread count.
//! \return #P by N
//! \throw InputError as shadowed_transfer does, or for an empty lobe set
RowMatrixXd sg_transfer(const RayScene& scene, const RowMatrixX3d& points, const RowMatrixX3d& normals, const SgBasis& basis,
                        const TransferOptions& options, const RowMatrixX3d* offsets = nullptr, const ProgressFn& progress = {});

//! The baseline for benchmarks: the same rays from the same points with the same thread
//! count, with nothing done but counting occluded rays.
//! \return the number of occluded rays
uint64_t bare_occlusion_loop(const RayScene& scene, const RowMatrixX3d& points,
                             const RowMatrixX3d& normals, const TransferOptions& options,
                             TransferStats* stats = nullptr, const RowMatrixX3d* offsets = nullptr);

//! Where a mesh vertex's rays start from: along the mean of the normals of every render
//! vertex at its position. At a crease that points off every face meeting there (into the
//! corner when concave, out when convex); offset along its own normal only, a vertex on a
//! concave crease would start in the other face's plane, and rays would leak through it.
//! Falls back to the vertex's own normal where the sides cancel (back-to-back sheets).
RowMatrixX3d vertex_offset_directions(const Mesh& mesh);

//! The same for vertices given by position index and normal (#P rows each).
RowMatrixX3d offset_directions(const std::vector<uint32_t>& position_of, const RowMatrixX3d& normals);

//! Validates options; \throw InputError naming the bad value.
void check_transfer_options(const TransferOptions& options);

}  // namespace prtsub
