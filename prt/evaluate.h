// Surface RMS transfer error of an asset against a high-ray reference on its source surface.
#pragma once

#include "prtsub/prt/albedo.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/transfer.h"

namespace prtsub {

struct ReferenceOptions {
  size_t points = 20000;  //!< area-stratified reference points on the source surface
  int rays = 2048;        //!< reference rays per point
  int order = 4;
  uint64_t seed = 20250;  //!< fixed: every asset from one source is judged on the same points
  int threads = 0;
  size_t noise_points = 2000;  //!< points traced twice to measure the reference's own noise
  //! Interreflection, for an asset baked with bounces: the reference adds the light of that many
  //! bounces, traced as paths through the source (path_transfer.h), never taken from the asset.
  int bounces = 0;
  double albedo = 0.8;
  //! A coloured albedo over the source (overrides `albedo`): the reference is RGB, #N by 3·N²,
  //! its bounces carried by each channel's albedo, to judge an RGB asset (docs/sh_convention.md,
  //! "Colour")
  std::shared_ptr<const AlbedoField> colour;
  int paths = 0;  //!< paths per point for the bounced light; 0: `rays`
};

//! Reference points with their transfer. The points depend only on the source and the seed.
struct Reference {
  RowMatrixX3d points, normals;      //!< #N by 3, on the source surface
  std::vector<uint32_t> source_face;  //!< #N: input triangle (as numbered by source_face)
  RowMatrixXd transfer;              //!< #N by K, at `rays` rays
  double noise_floor = 0;            //!< RMS of the reference's own error, relative to ‖t_unshadowed‖
  int rays = 0;
  int bounces = 0, paths = 0;  //!< the bounced light's (paths only when bounces > 0)
  double seconds_bounce = 0;
};

//! Seeded, area-stratified points on `source` (systematic sampling of cumulative area, one
//! random offset; uniform within each triangle), transfer at each: shadowed, plus with
//! `bounces` the light of that many bounces, traced as paths (docs/sh_convention.md).
//! \param progress told of reference points as they finish (each twice with bounces: direct
//!        light, then the paths), not of the noise floor's second trace
Reference make_reference(const Mesh& source, const RayScene& scene, const ReferenceOptions& options, const ProgressFn& progress = {});

struct EvalResult {
  double rms_percent = 0, p95_percent = 0, noise_floor_percent = 0;
  size_t points = 0, unlocated = 0;
  int reference_rays = 0;
};

//! ‖t_unshadowed‖, the same for every normal: the unit of every error we report.
double unshadowed_norm(int order);

//! Interpolates the asset's transfer at each reference point, found among the asset's faces
//! with the point's source_face (the one containing it, or the nearest). Error per point is
//! ‖g(p) − t_ref(p)‖ / ‖t_unshadowed‖; RMS and 95th percentile over points, in percent. RGB
//! transfer against an RGB reference: the RMS over the three channels of that error.
//! \throw InputError when one is RGB and the other is not
EvalResult evaluate(const Reference& reference, const RowMatrixX3d& positions, const std::vector<Triangle>& triangles,
                    const std::vector<uint32_t>& source_face, const RowMatrixXd& transfer);
//! The same for an asset whose faces do not lie in the source's (a simplified one): each
//! reference point is located at its closest point on the asset's surface (ties: the lower
//! face), and the asset's transfer interpolated there. The same for any thread count.
//! \param point_errors if given, each reference point's error (a fraction of ‖t_unshadowed‖), in
//!        the reference's order: where two assets differ (bench/eval_diff.cpp)
EvalResult evaluate_by_closest_point(const Reference& reference, const RowMatrixX3d& positions, const std::vector<Triangle>& triangles,
                                     const RowMatrixXd& transfer, int threads = 0, std::vector<double>* point_errors = nullptr);

}  // namespace prtsub
