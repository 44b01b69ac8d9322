// Interreflected transfer: light that bounces between the mesh's own surfaces (Sloan, Kautz and
// Snyder 2002), added to the direct (shadowed) transfer pass by pass. docs/sh_convention.md,
// "Interreflection", is the contract.
#pragma once

#include <vector>

#include "prtsub/prt/albedo.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/transfer.h"
#include "prtsub/subdiv/mesh.h"

namespace prtsub {

enum class BounceCache { Auto, On, Off };
BounceCache parse_bounce_cache(const std::string& name);  //!< auto, on, off \throw InputError
const char* bounce_cache_name(BounceCache c);

struct BounceOptions {
  //! Passes of interreflection; 0 is direct transfer only. With `until_converged`, the most.
  int bounces = 0;
  //! Stop after the first pass whose change (the RMS over the surface of ‖Δt‖, in eval's unit) is
  //! below `noise_percent`, the bake's own noise ("--bounces auto")
  bool until_converged = false;
  double noise_percent = 0;
  double albedo = 0.8;  //!< the diffuse albedo of every surface, in [0, 1]
  //! A coloured albedo over the mesh the passes run on (it overrides `albedo`): the transfer is
  //! then RGB, #V by 3·N², the channels' blocks side by side, each bounced by its own channel
  std::shared_ptr<const AlbedoField> colour;
  int rays = 256;       //!< rays per vertex and pass
  uint64_t seed = 0;
  int threads = 0;
  //! Keep each ray's hit (12 bytes) between passes, or trace it again each pass; Auto keeps
  //! them while they fit in `cache_limit_mib`. The results are the same either way.
  BounceCache cache = BounceCache::Auto;
  double cache_limit_mib = 1024;
  //! After the vertices' passes, bounce once more at the fit's surface samples and fit again, so
  //! the fit sees bounced light too (bake; a fit to samples of the input after simplification
  //! keeps the vertices' passes only)
  bool fit_samples = true;
};

struct BounceStats {
  int passes = 0;
  std::vector<double> change_percent;  //!< per pass: RMS over the surface of what it added
  uint64_t rays = 0;                   //!< traced (once with the cache, every pass without; and at the samples)
  uint64_t sample_rays = 0;            //!< bake: the fit's samples' bounce (BounceOptions::fit_samples)
  bool cached = false;
  double cache_mib = 0;
  double seconds = 0;
};

//! The direct transfer plus `bounces` passes of interreflection. Pass k adds, at every render
//! vertex p, (albedo/π) ∫ (1 − V(p, ω)) t_{k−1}(h(p, ω)) max(n·ω, 0) dω, where h is the first
//! surface hit along ω and t_{k−1}(h) is the previous pass's addition (the direct transfer for
//! k = 1) interpolated barycentrically in the hit triangle, from its own corners (so from the
//! side of a crease that faces the ray). A ray that hits a triangle's back contributes nothing:
//! a back face is taken as black. R cosine-weighted directions per vertex (a shifted lattice,
//! seeded per vertex, the same every pass) estimate the integral as (albedo/R) Σ_hits t_{k−1}(h).
//! The result does not depend on the thread count or on the cache.
//! \param direct #V by N², the vertices' direct transfer (the asset's values); with
//!        `options.colour`, the result is #V by 3·N² (docs/sh_convention.md, "Colour")
//! \throw InputError for options out of range, EmbreeError
//! \param before_last if given, receives the transfer before the last pass (the direct transfer
//!        plus passes 1..N−1): what the last pass bounced, which gather_bounce bounces once more
//!        at other points
RowMatrixXd interreflected_transfer(const Mesh& mesh, const RayScene& scene, const RowMatrixXd& direct, const BounceOptions& options,
                                    BounceStats* stats = nullptr, RowMatrixXd* before_last = nullptr);

//! One bounce gathered at surface points that need not be vertices (the fit's samples): at each,
//! (albedo/R) Σ over R cosine-weighted rays of `values` interpolated in the front face each hits,
//! as a pass of interreflected_transfer does at a vertex (point i's rays are its own stream of
//! options.seed). The same for any thread count.
//! \param values #V by K on `mesh`'s render vertices, whose triangles `scene` holds in order;
//!        with `options.colour`, K = 3·N², the three channels' blocks
//! \param offsets #P by 3 unit directions the rays leave along (the samples' own)
//! \throw InputError for options out of range, EmbreeError
RowMatrixXd gather_bounce(const Mesh& mesh, const RayScene& scene, const RowMatrixXd& values, const RowMatrixX3d& points,
                          const RowMatrixX3d& normals, const RowMatrixX3d& offsets, const BounceOptions& options,
                          TransferStats* stats = nullptr);

//! The noise of the light that `options.bounces` passes at options.rays rays per vertex would add
//! to `direct`, before they run: the surface's mean (area-weighted over a systematic subset of at
//! most `points` vertices, halved as interpolation spreads it, per channel), from pass 1's noise
//! in two gathers with seeds of their own, grown by (Σ_{k<B}(ρh)^k)², h each vertex's fraction
//! of rays that hit a front face: an estimate from above (the .cpp says why). Adds its rays to *rays.
//! \param direct #V by N², the direct light (grey, also with options.colour)
//! \throw InputError for options out of range or shapes that do not match, EmbreeError
double bounce_noise(const Mesh& mesh, const RayScene& scene, const RowMatrixXd& direct, const BounceOptions& options, size_t points,
                    uint64_t* rays);

//! The baseline for benchmarks: one pass's rays (the same directions from the same vertices, with
//! the same threads) through Embree's closest-hit query, with nothing done but counting hits.
//! \return the number of rays that hit anything
uint64_t bare_bounce_loop(const Mesh& mesh, const RayScene& scene, const BounceOptions& options, TransferStats* stats = nullptr);

}  // namespace prtsub
