// Where the fit's surface samples go: a pilot pass finds the faces where interpolating the
// vertex values fails, and only those get samples.
#pragma once

#include <string>
#include <vector>

#include "prtsub/prt/surface_samples.h"
#include "prtsub/prt/transfer.h"

namespace prtsub {

//!  - Area: every face of positive area gets samples, in proportion to its area (the paper's).
//!  - Pilot: a pilot pass measures, face by face, how far the signal is from the interpolated
//!    vertex values beyond what their noise explains. Faces where it is not significantly
//!    different get no samples (the fit takes the interpolant as their data); the others share
//!    the budget by area and by that difference.
enum class SampleAllocation { Area, Pilot };
SampleAllocation parse_sample_allocation(const std::string& name);  //!< area, pilot \throw InputError
const char* sample_allocation_name(SampleAllocation a);

struct PilotOptions {
  double per_triangle = 2;  //!< pilot samples per triangle (one each from 1 up, the rest by area; below 1 by area) ...
  //! ... and at least this many in all: a coarse mesh's large faces need several each to show a
  //! shadow inside them, and on a small mesh they cost nothing. The fit's samples have the same
  //! floor, over the faces the pilot gives any.
  size_t min_samples = 4096;
  //! rays per pilot sample: its test weighs ‖r‖² against the noise v, whose spread falls as
  //! 1/rays but only as 1/√samples, so a few well-traced samples find more than many noisy ones
  int rays = 32;
  //! a face pools the pilot samples of the faces within this many vertex rings of it (1: the
  //! faces sharing a corner with it; 2: theirs too): a subtle bias spread over a region shows
  //! only in a wider pool
  int rings = 2;
  //! a face needs samples when its pool's mean excess residual is this many of its own
  //! standard errors above zero
  double significance = 2;
  //! share of a face's sample density that follows its area alone; the rest follows its
  //! estimated interpolation error (a floor against a pilot that missed a shadow)
  double area_share = 0.5;
  //! pilot samples kept with their values as a hold-out set (every ⌈S / holdout⌉-th of the first stage)
  size_t holdout = 262144;
  //! Two stages when in (0, 1): this share of the samples first, everywhere; the rest only on
  //! faces whose first-stage pool exceeds `first_significance` standard errors, so a pilot over
  //! a mesh that interpolation already serves costs little more than its first stage.
  double first_share = 0.5;
  double first_significance = 1;
  //! The values are shadowed transfer whose unshadowed curvature the fit projects exactly
  //! (FitOptions::unshadowed_order): test what is left after the known part w·t_u(n) (w the open
  //! share, interpolated), so that a face is sampled for a shadow inside it, not for the curvature
  //! of t_u that needs no rays.
  bool exact_unshadowed = false;
  //! Candidate rays per fit sample (choose_sample_rays): when not empty, each one's noise is
  //! measured on up to `noise_points` of the samples traced on faces still in question after the
  //! last stage (each traced twice, independently),
  //! and the variation the samples are there to find is the sampled faces' mean excess. The
  //! measurement costs at most an eighth of the pilot's rays, and is skipped below 64 points.
  std::vector<int> sample_ray_choices;
  size_t noise_points = 1000;
  //! The screen: before the pilot proper, up to `screen_samples` of its hold-out samples (spread
  //! over the surface) are traced, and their area-weighted mean excess Σw·d compared with the
  //! interpolated vertex noise Σw·Σh²·var x̂ at the same points. When that ratio is below
  //! `screen_ratio`, the signal's variation inside the faces is smaller than the noise the
  //! vertices' own rays leave (a dense scan): the pilot stops there, no face gets samples, and the
  //! screen's samples are the hold-out. 0: no screen. (The decision is on the estimate itself:
  //! its delta-method standard error, reported, is inflated by the heavy tails of AO's noise,
  //! 0.44 on armadillo where three seeds gave 0.35, 0.55 and 0.73; the shared scenes lie at
  //! 0.18–2.6 for the scans and 13 or more for every other mesh.)
  double screen_ratio = 1;
  size_t screen_samples = 65536;
};

//! What the pilot measured for the rays per fit sample, and (filled by choose_sample_rays) the choice.
struct SampleRaysChoice {
  int rays = 0;                 //!< chosen (0: none yet, or nothing measured: nothing sampled, or no candidates)
  double variation = 0;         //!< ‖β‖², the interpolation error's mean square per sample on the sampled faces
  std::vector<int> choices;     //!< the candidates, as asked
  std::vector<double> noise;    //!< per candidate: one sample's measured variance (summed over its K values)
  std::vector<double> cost;     //!< per candidate: its predicted moment error at the budget (choose_sample_rays)
  size_t points = 0;            //!< samples the noise was measured on
  uint64_t rays_traced = 0;     //!< their rays (in SamplePlan::rays too)
};

//! Which rays per sample a budget of `face_rays` sample rays per sampled face should buy: with Q
//! rays a face gets n = B/Q samples, and its moments' error is about variation/n² + noise(Q)/n.
//! The noise is independent from sample to sample (1/n); the samples of a face form a lattice,
//! so what they see of the signal's variation averages out as 1/n² where it is smooth (and
//! between 1/n^1.5 and 1/n² across a shadow edge). It keeps 16 on sibenik and house_on_site,
//! where 4 loses to 16 at the same sample rays (docs/fit.md). The model is rough (the variation's
//! exponent lies between 1.5 and 2), so the choice leaves `given` (when it is a candidate) only for
//! a modelled error below `keep` times given's: a gain the model is sure of. Fills c.cost and c.rays.
//! \throw InputError when c holds no measurement (noise and choices of equal, non-zero size) or face_rays ≤ 0
void choose_sample_rays(SampleRaysChoice& c, double face_rays, int given = 0, double keep = 0.8);

//! A systematic subset of the pilot's samples, kept with their traced values: a hold-out set,
//! independent of the vertex and sample rays, on which the finished asset's error can be
//! measured (holdout_error in error_estimate.h).
struct Holdout {
  std::vector<uint32_t> face;
  RowMatrixX3d barycentric;     //!< n by 3
  std::vector<double> weight;   //!< each sample's area weight (its face's area over its count)
  std::vector<double> variance;  //!< each value's estimated variance, summed over its K values
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> values;  //!< n by K
  //! rays each value was traced with (every sample the same); 0 where the values are not
  //! shadowed transfer alone (bounced_holdout's), which sharpen_holdout cannot trace more of
  int rays = 0;
  size_t size() const { return face.size(); }
};

//! What the pilot found: per-face sample weights for make_surface_samples, and figures.
struct SamplePlan {
  std::vector<double> face_weight;  //!< #F: 0 where interpolation suffices, else relative density
  size_t pilot_drawn = 0;           //!< drawn by make_pilot_samples
  size_t pilot_samples = 0;         //!< traced (with two stages, fewer than drawn)
  size_t sampled_faces = 0;         //!< faces with a positive weight
  double sampled_area = 0;          //!< their area
  Holdout holdout;                  //!< at most PilotOptions::holdout of the pilot samples
  size_t screen_samples = 0;        //!< traced by the screen (0: no screen)
  double screen_ratio = 0;          //!< the screen's excess over the vertex noise (inf where that noise is 0)
  double screen_standard_error = 0;
  bool screened_out = false;        //!< the pilot stopped after the screen: no face is sampled
  SampleRaysChoice sample_rays;     //!< with PilotOptions::sample_ray_choices: the rays per fit sample
  uint64_t rays = 0;
  double seconds = 0;
};

//! The pilot's samples: `options.per_triangle` per face (at least `min_samples` in all), one on
//! each face of positive area and the rest by area.
SurfaceSamples make_pilot_samples(const Mesh& mesh, const PilotOptions& options, uint64_t seed);

//! The pilot pass: `pilot` (from make_pilot_samples) traced with `options.rays` (at least 2, for
//! a variance) and the order, seed and threads of `rays`, each compared with the prior
//! interpolated at it.
//! \param prior #V by K, the vertices' point values; prior_variance #V, their variances
//! \throw InputError for shapes that do not match the mesh
SamplePlan plan_samples(const Mesh& mesh, const RayScene& scene, const SurfaceSamples& pilot, const RowMatrixXd& prior,
                        const std::vector<double>& prior_variance, const TransferOptions& rays,
                        const PilotOptions& options, const ProgressFn& progress = {});

}  // namespace prtsub
