// Interreflected transfer traced as paths through the surface: the reference that eval and
// render --reference judge a bounced asset against. It shares nothing with the asset: no vertex,
// no interpolated pass, only the surface itself.
#pragma once

#include <vector>

#include "prtsub/prt/albedo.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/transfer.h"

namespace prtsub {

struct PathOptions {
  int order = 4;
  int paths = 2048;  //!< per point
  int bounces = 1;   //!< bounces of light each path may take, 1..64
  double albedo = 0.8;
  //! A coloured albedo over the surface (overrides `albedo`): the result is then RGB, #P by 3·N²,
  //! each channel's block carried by that channel's albedo at every hit
  std::shared_ptr<const AlbedoField> colour;
  uint64_t seed = 0;  //!< the result is a function of (seed, point index), not of threads
  int threads = 0;
  //! false: only the bounced light (add shadowed_transfer's direct transfer for the total), with
  //! a control variate at each bounce. true: the plain estimator of the total, direct light
  //! included, with none: the brute-force check the other is tested against.
  bool plain = false;
};

//! The surface the paths bounce on: render vertices with their shading normals, and the triangles
//! of `scene` in the same order (the scene's primitive f is triangles[f]).
struct PathSurface {
  const RowMatrixX3d& positions;  //!< #V by 3
  const RowMatrixX3d& normals;    //!< #V by 3
  const std::vector<Triangle>& triangles;
};

//! At each point p (normal n): the transfer that arrives after 1..B bounces, with the asset's
//! rules (docs/sh_convention.md, "Interreflection"): albedo/π times the cosine-weighted transfer
//! of the surface p sees, back faces black. With `plain`, the whole t_B(p) instead.
//! \param variance if given, receives #P estimates of each result's variance (summed over its
//!        N² values): the paths are independent, so their spread over the count
//! \return #P by N² (by 3·N² with `options.colour`)
//! \throw InputError for options out of range, EmbreeError
RowMatrixXd path_traced_transfer(const RayScene& scene, const PathSurface& surface, const RowMatrixX3d& points,
                                 const RowMatrixX3d& point_normals, const PathOptions& options, std::vector<double>* variance = nullptr,
                                 TransferStats* stats = nullptr, const ProgressFn& progress = {});

}  // namespace prtsub
