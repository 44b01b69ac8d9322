// The bake's own measure of its asset's error: what `prtsub eval` would report, without a
// reference, from samples held out of every estimate the asset was built from.
#pragma once

#include "prtsub/prt/path_transfer.h"
#include "prtsub/prt/sample_plan.h"

namespace prtsub {

struct ErrorEstimate {
  double percent = 0;         //!< the surface RMS of ‖f − g‖, in % of ‖t_unshadowed‖ (eval's unit)
  double standard_error = 0;  //!< of `percent`, from the spread of the samples' terms
  size_t samples = 0;
};

//! E² = Σ_k w_k (‖f̂_k − g(p_k)‖² − v_k) / Σ_k w_k over the hold-out samples k: f̂_k their traced
//! values, v_k their variances, g the asset's interpolated values. Each term is an unbiased
//! estimate of ‖f − g‖² at p_k, as long as f̂_k's rays are independent of those g was made from.
//! \param values #V by K, the asset's vertex values (order-1 transfer for AO); #V by 3·N² for RGB
//!        transfer, whose error is the RMS over the three channels, as eval's
//! \throw InputError for shapes that do not match
ErrorEstimate holdout_error(const Mesh& mesh, const Holdout& holdout, const RowMatrixXd& values);

//! At most `count` of the hold-out's samples, every ⌈n / count⌉-th (a systematic subset, which
//! keeps the samples' spread over the surface), with their weights, values and variances.
Holdout holdout_subset(const Holdout& holdout, size_t count);

//! The hold-out with less noise: each sample traced again at `options.rays` more rays (the seed,
//! order, estimator and threads of `options`; give it a seed no other rays of the asset share),
//! at the point, normal and offset the pilot traced it at, and the two estimates merged by their
//! rays. A term of holdout_error varies mostly with its sample's noise v where v is far above the
//! error itself (a dense scan), and that spread falls as 1/rays but only as 1/√samples: four
//! times the rays halve holdout_error's standard error at the cost of four times the samples.
//! \throw InputError where holdout.rays is 0 (bounced values), options.rays < 1, shapes that do
//! not match or a face not on the mesh; EmbreeError
Holdout sharpen_holdout(const Mesh& mesh, const RayScene& scene, const Holdout& holdout, const TransferOptions& options,
                        TransferStats* stats = nullptr, const ProgressFn& progress = {});

//! The same at points the caller keeps, for a hold-out drawn on another surface than the
//! asset's (a simplified asset's, drawn on its source): `points`, `normals` and `offsets` are
//! each sample's, as it was first traced (one row per sample).
//! \throw InputError as sharpen_holdout; EmbreeError
Holdout sharpen_holdout_at(const RowMatrixX3d& points, const RowMatrixX3d& normals, const RowMatrixX3d& offsets, const RayScene& scene,
                           const Holdout& holdout, const TransferOptions& options, TransferStats* stats = nullptr,
                           const ProgressFn& progress = {});

//! The hold-out for a bounced asset: each sample's reference gains the light of `options.bounces`
//! bounces, path-traced through the surface from the sample's point (path_traced_transfer: eval's
//! own reference, which never reads the asset's values), and its paths' variance joins the
//! sample's, so holdout_error stays an unbiased estimate of eval's error against bounced light.
//! With `options.colour` the values become RGB (3·N², every channel's direct light the same).
//! \param scene holds `mesh`'s triangles in order (position_triangles), which the paths bounce on
//! \throw InputError for shapes that do not match, EmbreeError
Holdout bounced_holdout(const Mesh& mesh, const RayScene& scene, const Holdout& holdout, const PathOptions& options,
                        TransferStats* stats = nullptr);

//! Two sets of values judged on the same held-out samples, paired: the weighted mean over the
//! samples of ‖f̂_k − a(p_k)‖² − ‖f̂_k − b(p_k)‖², how much lower b's squared error is than a's
//! (in the values' unit squared), and its standard error. Each sample's own noise cancels in the
//! difference, and so does most of the spread of the terms, so a difference far too small to
//! show in either error's standard error can still be told from zero, or not.
struct ErrorDifference {
  double mean = 0;
  double standard_error = 0;
};
ErrorDifference holdout_difference(const Mesh& mesh, const Holdout& holdout, const RowMatrixXd& a, const RowMatrixXd& b);

}  // namespace prtsub
