// The library's one entry point, called as a consumer would: a mesh built in memory, options as
// structs, progress through callbacks, nothing printed.
#include "prtsub/prt/bake.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <map>
#include <mutex>
#include <numeric>

#include "helpers.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/sh.h"
#include "prtsub/prt/unshadowed_projection.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/version.h"

namespace prtsub {
namespace {

Mesh sphere_on_plane() { return test::build(test::merge(test::icosphere(1), test::quad(2.5, -1.0, true))); }

TEST(Bake, AdaptiveRefinementIsIdenticalForAnyThreadCount) {
  const Mesh mesh = sphere_on_plane();
  BakeOptions o;
  o.refine = Refinement::Adaptive, o.adaptive.budget = 900, o.adaptive.batch = 16;
  o.transfer.rays = 32, o.transfer.threads = 1;
  const BakeResult one = bake(mesh, o);
  o.transfer.threads = 2;
  const BakeResult two = bake(mesh, o);
  EXPECT_EQ(one.mesh.triangles, two.mesh.triangles);
  EXPECT_EQ((one.transfer - two.transfer).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(one.mesh.num_faces(), 900u);
}

TEST(Bake, ProjectingTheUnshadowedPartLowersTheErrorOfASmoothSurface) {
  // A sphere: every vertex sees its whole hemisphere (its transfer is t_u(n_i), exact), and inside
  // a face only the sliver below the facet's plane is shaded. What interpolation misses there is
  // mostly t_u's curvature in n, which the default now projects exactly instead of sampling.
  const Mesh mesh = test::build(test::icosphere(3));
  BakeOptions o;
  o.transfer.rays = 32, o.transfer.threads = 1;
  const BakeResult projected = bake(mesh, o);
  o.unshadowed_projection = false;
  const BakeResult before = bake(mesh, o);
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 4000, ro.rays = 1024, ro.threads = 1;
  const Reference ref = make_reference(mesh, scene, ro);
  auto error = [&](const BakeResult& b) {
    return evaluate(ref, vertex_positions(b.mesh), b.mesh.triangles, b.mesh.source_face, b.transfer).rms_percent;
  };
  std::printf("sphere: %.3f%% projected (%zu faces sampled), %.3f%% before (%zu), reference floor %.3f%%\n", error(projected),
              projected.fit_data.plan.sampled_faces, error(before), before.fit_data.plan.sampled_faces, ref.noise_floor);
  EXPECT_LT(error(projected), 0.8 * error(before));
  EXPECT_LT(projected.fit_data.plan.sampled_faces, before.fit_data.plan.sampled_faces);
}

TEST(Bake, AlphaAutoKeepsTheCandidateWhoseFitHasTheLowestHeldOutError) {
  const Mesh mesh = sphere_on_plane();
  BakeOptions o;
  o.transfer.rays = 64, o.transfer.threads = 1;
  const BakeResult a = bake(mesh, o);
  ASSERT_GE(a.alpha_trials.size(), 2u);
  ASSERT_GT(a.fit_data.plan.sampled_faces, 0u);
  // The asset is the kept candidate's fit; the search moves on only while a candidate is better,
  // so it stops at the one after the kept one (or at the last), and the kept one is the best of
  // those before it.
  size_t kept = 0;
  while (a.alpha_trials[kept].first != a.alpha) ++kept;
  EXPECT_EQ(a.predicted.percent, a.alpha_trials[kept].second);
  EXPECT_TRUE(kept + 2 == a.alpha_trials.size() || kept + 1 == 3u);
  for (size_t k = 0; k < kept; ++k) EXPECT_GT(a.alpha_trials[k].second, a.alpha_trials[kept].second);
  // The candidates differ: the choice is not idle.
  EXPECT_NE(a.alpha_trials[0].second, a.alpha_trials[1].second);
  // Given that α outright, the bake is the same asset bit for bit.
  o.alpha_auto = false, o.fit.alpha = a.alpha;
  const BakeResult b = bake(mesh, o);
  EXPECT_TRUE(b.alpha_trials.empty());
  EXPECT_EQ((a.transfer - b.transfer).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Bake, WhereThePilotsScreenStopsItTheSampleRaysGoToTheVerticesAndNothingIsFitted) {
  // A screen asked to stop at any ratio: no face sampled, no α tried (every α would give the same
  // values), each vertex its prior corrected by the known part alone; the rest of the pilot and
  // the samples are not traced, and the second round of vertex rays gets at least as many rays.
  // (This mesh is too small for that round: the pilot's floor of 4096 samples outspends what
  // sampling every face would.)
  const Mesh mesh = sphere_on_plane();
  BakeOptions o;
  o.transfer.rays = 64, o.transfer.threads = 1;
  o.pilot.screen_ratio = 1e6;
  const BakeResult a = bake(mesh, o);
  ASSERT_TRUE(a.fit_data.plan.screened_out);
  EXPECT_EQ(a.fit_data.plan.sampled_faces, 0u);
  EXPECT_EQ(a.fit_data.samples.size(), 0u);
  EXPECT_TRUE(a.alpha_trials.empty());
  EXPECT_EQ(a.fit.unsupported, a.mesh.num_vertices());
  FitOptions f = resolve_bake_options(o).fit;
  EXPECT_EQ((a.transfer - fit_prior(a.mesh, a.point, f)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(a.fit_data.plan.holdout.size(), a.fit_data.plan.screen_samples);
  EXPECT_GT(a.predicted.samples, 0u);
  o.pilot.screen_ratio = 0;
  const BakeResult b = bake(mesh, o);
  EXPECT_GT(b.fit_data.plan.sampled_faces, 0u);
  EXPECT_GE(a.top_up.rays, b.top_up.rays);
  EXPECT_EQ(a.fit_data.rays, uint64_t(o.pilot.rays) * a.fit_data.plan.screen_samples);
  EXPECT_LT(a.rays, b.rays);
}

TEST(Bake, RaysPerSampleAreChosenForTheSameSampleRays) {
  // The same sample rays, split by what the pilot measures: the choice is the modelled error's
  // least, the sample rays are what the fixed 16 rays per sample spend, and on an independent
  // reference the asset is no worse. Both scenes have a few thousand samples (the pilot's floor)
  // on few sampled faces: many per face, so the variation is averaged out and rays pay (32). The
  // choice of 4, where many faces share the budget (conference), is SampleRays' closed form.
  struct Case {
    Mesh mesh;
    bool contact;
  };
  const Case cases[] = {{test::build(test::merge(test::grid(16, 0.3), test::transformed(test::cube(), 0.3, Eigen::Vector3d(0.35, 0.35, 0.02)))), true},
                        {sphere_on_plane(), false}};
  for (const Case& k : cases) {
    BakeOptions o;
    o.transfer.rays = 64, o.transfer.threads = 1;
    o.samples.per_triangle = 2;
    const BakeResult chosen = bake(k.mesh, o);
    const SampleRaysChoice& c = chosen.fit_data.plan.sample_rays;
    ASSERT_EQ(c.cost.size(), 3u);
    EXPECT_EQ(chosen.fit_data.sample_rays, c.rays);
    const size_t best = size_t(std::min_element(c.cost.begin(), c.cost.end()) - c.cost.begin());
    EXPECT_EQ(c.rays, c.choices[best]);
    EXPECT_EQ(c.rays, 32) << c.variation << " " << c.noise[0] << " " << c.noise[1];
    EXPECT_GT(c.noise[0], c.noise[1]);
    EXPECT_GT(c.noise[1], c.noise[2]);
    o.sample_rays_auto = false;
    const BakeResult fixed = bake(k.mesh, o);
    EXPECT_EQ(fixed.fit_data.sample_rays, 16);
    EXPECT_TRUE(fixed.fit_data.plan.sample_rays.noise.empty());
    EXPECT_EQ(chosen.fit_data.plan.face_weight, fixed.fit_data.plan.face_weight);
    const double rays_chosen = double(chosen.fit_data.samples.size()) * chosen.fit_data.sample_rays;
    const double rays_fixed = double(fixed.fit_data.samples.size()) * fixed.fit_data.sample_rays;
    EXPECT_NEAR(rays_chosen / rays_fixed, 1.0, 0.01) << rays_chosen << " " << rays_fixed;
    const RayScene scene(k.mesh.positions, position_triangles(k.mesh));
    ReferenceOptions ro;
    ro.points = 4000, ro.rays = 1024, ro.threads = 1;
    const Reference ref = make_reference(k.mesh, scene, ro);
    auto error = [&](const BakeResult& b) {
      return evaluate(ref, vertex_positions(b.mesh), b.mesh.triangles, b.mesh.source_face, b.transfer).rms_percent;
    };
    std::printf("%s: %.3f%% at %d rays per sample, %.3f%% at 16\n", k.contact ? "box over a ground" : "sphere on a plane", error(chosen),
                c.rays, error(fixed));
    EXPECT_LT(error(chosen), error(fixed));
    // Any thread count: the same measurements and the same asset.
    o.sample_rays_auto = true, o.transfer.threads = 2;
    const BakeResult two = bake(k.mesh, o);
    EXPECT_EQ(two.fit_data.plan.sample_rays.noise, c.noise);
    EXPECT_EQ((two.transfer - chosen.transfer).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(Bake, InMemoryMeshGivesAnAssetWithItsStagesReportedAndNothingElseTouched) {
  const Mesh mesh = sphere_on_plane();
  BakeOptions o;
  o.transfer.rays = 16, o.sample_rays = 4, o.samples.per_triangle = 16;
  o.pilot.rays = 16, o.pilot.per_triangle = 1, o.pilot.min_samples = 0;  // a pilot cheap enough to leave rays for the vertices
  o.source = "sphere on plane";
  std::mutex m;
  std::map<std::string, size_t> totals, done;
  std::string current;
  BakeProgress progress;
  progress.stage = [&](const char* stage, size_t total) { current = stage, totals[stage] = total; };
  progress.add = [&](size_t n) {
    std::lock_guard<std::mutex> lock(m);
    done[current] += n;
  };
  const BakeResult r = bake(mesh, o, progress);
  EXPECT_EQ(r.mesh.num_faces(), mesh.num_faces());
  ASSERT_EQ(r.transfer.rows(), static_cast<Eigen::Index>(mesh.num_vertices()));
  EXPECT_EQ(r.transfer.cols(), sh_count(4));
  EXPECT_TRUE(r.transfer.allFinite());
  EXPECT_EQ(totals["transfer"], mesh.num_vertices());
  EXPECT_EQ(done["transfer"], mesh.num_vertices());
  EXPECT_EQ(totals["samples"], r.fit_data.samples.size());
  EXPECT_EQ(done["samples"], r.fit_data.samples.size());
  // The pilot found where interpolation fails, and the rays it saved went to noisy vertices.
  ASSERT_EQ(r.fit_data.allocation, SampleAllocation::Pilot);
  EXPECT_EQ(totals["pilot"], r.fit_data.plan.pilot_drawn);
  EXPECT_EQ(done["pilot"], r.fit_data.plan.pilot_drawn);  // two stages: the untraced rest completes the bar
  EXPECT_LT(r.fit_data.plan.pilot_samples, r.fit_data.plan.pilot_drawn);
  EXPECT_EQ(totals["vertex rays"], r.top_up.vertices);
  EXPECT_EQ(done["vertex rays"], r.top_up.vertices);
  EXPECT_GT(r.top_up.rays, 0u);
  EXPECT_LT(r.top_up.variance_after, r.top_up.variance_before);
  EXPECT_GT(r.fit_data.plan.sampled_faces, 0u);
  // Its held-out samples measure the finished asset's error.
  EXPECT_EQ(r.predicted.samples, r.fit_data.plan.holdout.size());
  EXPECT_GT(r.predicted.samples, 0u);
  EXPECT_GT(r.predicted.percent, 0.0);
  EXPECT_EQ(r.fit_data.plan.rays, uint64_t(o.pilot.rays) * r.fit_data.plan.pilot_samples);
  EXPECT_EQ(r.rays, uint64_t(16) * mesh.num_vertices() + r.fit_data.plan.rays + uint64_t(4) * r.fit_data.samples.size() + r.top_up.rays);
  std::map<std::string, std::string> meta(r.metadata.begin(), r.metadata.end());
  EXPECT_EQ(meta["generator"], std::string("prtsub ") + kVersion);
  EXPECT_EQ(meta["source"], "sphere on plane");
  EXPECT_EQ(meta["fit"], "lsq");
  EXPECT_EQ(meta["refine"], "none");
  // The point values ride along: the fit moved them, and not by much on a smooth signal.
  EXPECT_GT((r.point - r.transfer).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Bake, AnErrorTargetAddsVertexRaysUntilTheHeldOutErrorMeetsIt) {
  // A fine ground under a high half-plane with 4 rays per vertex: its transfer changes slowly,
  // so noise dominates and a target 20% below the default's own error is reachable with more
  // vertex rays; one below the interpolation error is not, and says so.
  const Mesh mesh = test::build(test::merge(test::grid(16, 0.3), test::quad(50, 0.4, false, 0.5)));
  BakeOptions o;
  o.transfer.rays = 4;
  o.vertex_share = 0;  // no second round by default: the target alone adds vertex rays
  const BakeResult plain = bake(mesh, o);
  ASSERT_GT(plain.predicted.percent, 0.0);
  o.target_error = 0.8 * plain.predicted.percent;
  const BakeResult met = bake(mesh, o);
  EXPECT_LE(met.predicted.percent, o.target_error);
  EXPECT_GT(met.target_rays, 0u);
  EXPECT_EQ(met.rays, plain.rays + met.target_rays);
  EXPECT_GT(*std::max_element(met.vertex_rays.begin(), met.vertex_rays.end()), 4.0);
  EXPECT_TRUE(met.warnings.empty()) << met.warnings.front();
  // A target that needs many times the rays the vertices hold: no round may more than double
  // them (a plan sized on the room E² − bias² alone can overshoot it many times); the rounds
  // measure again as they go, and together they meet it.
  double held = 0;
  for (double v : plain.vertex_rays) held += v;
  o.target_error = 0.4 * plain.predicted.percent;
  const BakeResult far = bake(mesh, o);
  std::printf("--error %.3f: %d rounds, %llu rays on %.0f held\n", o.target_error, far.target_rounds,
              (unsigned long long)far.target_rays, held);
  EXPECT_LE(far.predicted.percent, o.target_error);
  EXPECT_GE(far.target_rounds, 2);
  EXPECT_LE(double(far.target_rays), (std::ldexp(1.0, far.target_rounds) - 1) * held);
  o.target_error = 0.001;  // far below what 512 ground triangles can interpolate
  const BakeResult unreachable = bake(mesh, o);
  ASSERT_FALSE(unreachable.warnings.empty());
  EXPECT_NE(unreachable.warnings.back().find("--error"), std::string::npos);
  o.target_error = -1;
  EXPECT_THROW(bake(mesh, o), InputError);
}

TEST(Bake, AnErrorTargetThatInterpolationHoldsUpGivesTheFitMoreSamples) {
  // A sphere on a ground of two triangles, 256 rays per vertex: what is left is the contact
  // shadow inside the big ground faces, which vertex rays do not lower and samples do. The fit
  // starts starved (one sample per face) so that more of them matter.
  const Mesh mesh = sphere_on_plane();
  BakeOptions o;
  o.transfer.rays = 256, o.samples.per_triangle = 1, o.pilot.min_samples = 64, o.vertex_share = 0;
  const BakeResult plain = bake(mesh, o);
  ASSERT_GT(plain.predicted.percent, 0.0);
  o.target_error = 0.9 * plain.predicted.percent;
  const BakeResult more = bake(mesh, o);
  EXPECT_GE(more.target_sample_rounds, 1);
  EXPECT_GT(more.target_samples, 3 * plain.fit_data.samples.size() - 1);  // the first round triples them
  EXPECT_EQ(more.fit_data.samples.size(), plain.fit_data.samples.size() + more.target_samples);
  EXPECT_EQ(more.rays, plain.rays + more.target_rays + more.target_sample_rays + more.target_holdout_rays);
  // Rays that sharpened the hold-out (if its standard error asked for them) are whole passes over it.
  const Holdout& held = more.fit_data.plan.holdout;
  EXPECT_EQ(more.target_holdout_rays, uint64_t(held.rays - o.pilot.rays) * held.size());
  EXPECT_EQ(more.target_sample_rays, uint64_t(o.sample_rays) * more.target_samples);
  EXPECT_LT(more.predicted.percent, plain.predicted.percent);
  // Judged independently, on a reference of its own: the asset is better, not just its estimate.
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 4000, ro.rays = 1024;
  const Reference ref = make_reference(mesh, scene, ro);
  const double e_plain = evaluate(ref, vertex_positions(plain.mesh), plain.mesh.triangles, plain.mesh.source_face, plain.transfer).rms_percent;
  const double e_more = evaluate(ref, vertex_positions(more.mesh), more.mesh.triangles, more.mesh.source_face, more.transfer).rms_percent;
  EXPECT_LT(e_more, 0.97 * e_plain) << e_plain;
  // Thread counts do not change the rounds.
  o.transfer.threads = 1;
  const BakeResult one = bake(mesh, o);
  EXPECT_EQ((one.transfer - more.transfer).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Bake, AnErrorTargetTracesANoisyHoldOutAgainUntilItsMeasureIsSharp) {
  // A small hold-out at 4 rays per sample: the estimate's standard error is a large share of it.
  // A loose target is met at once, and the hold-out is traced again (more rays per sample, the
  // same samples) until the standard error is at most 8% of the estimate, which an independent
  // reference then confirms within three of them.
  const Mesh mesh = sphere_on_plane();
  BakeOptions o;
  o.transfer.rays = 64, o.pilot.rays = 4, o.pilot.holdout = 400;
  const BakeResult plain = bake(mesh, o);
  ASSERT_EQ(plain.fit_data.plan.holdout.rays, 4);
  o.target_error = 2 * plain.predicted.percent + 1;
  const BakeResult r = bake(mesh, o);
  const Holdout& held = r.fit_data.plan.holdout;
  std::printf("hold-out of %zu samples: %.3f%% +- %.3f%% at 4 rays, %.3f%% +- %.3f%% at %d\n", held.size(), plain.predicted.percent,
              plain.predicted.standard_error, r.predicted.percent, r.predicted.standard_error, held.rays);
  ASSERT_GT(plain.predicted.standard_error, 0.08 * plain.predicted.percent);  // else this tests nothing
  EXPECT_GT(held.rays, 4);
  EXPECT_EQ(held.rays % 4, 0);
  EXPECT_LE(r.predicted.standard_error, 0.08 * r.predicted.percent);
  EXPECT_EQ(r.target_holdout_rays, uint64_t(held.rays - 4) * held.size());
  EXPECT_EQ(r.rays, plain.rays + r.target_holdout_rays);
  EXPECT_EQ((r.transfer - plain.transfer).cwiseAbs().maxCoeff(), 0.0);  // measured, not changed
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 4000, ro.rays = 1024;
  const Reference ref = make_reference(mesh, scene, ro);
  const double e = evaluate(ref, vertex_positions(r.mesh), r.mesh.triangles, r.mesh.source_face, r.transfer).rms_percent;
  const double clean = std::sqrt(std::max(0.0, e * e - ref.noise_floor * ref.noise_floor));
  EXPECT_NEAR(clean, r.predicted.percent, 3 * r.predicted.standard_error + 0.05 * clean) << e;
}

TEST(Bake, WithBouncesAnErrorTargetIsMeasuredOnTheBouncedAssetAndEvalAgrees) {
  // A sphere on a ground with 2 bounces at albedo 0.8: the ground under the sphere gets much of
  // its light from it. The prediction must be the bounced asset's (eval's reference with paths,
  // never the asset, judges the same), and above the direct light's alone.
  const Mesh mesh = sphere_on_plane();
  BakeOptions o;
  o.transfer.rays = 64, o.bounce.bounces = 2, o.target_error = 50;  // loose: met at once, measured
  const BakeResult r = bake(mesh, o);
  ASSERT_GT(r.predicted_direct.samples, 0u);
  EXPECT_EQ(r.target_bounce_rounds + r.target_direct_rounds, 0);
  EXPECT_GT(r.target_holdout_rays, 0u);
  // The room a loose target leaves: fewer bounce rays than the direct light's 64, as a power of two from 8.
  EXPECT_EQ(r.bounce_rays, r.bounce_rays_chosen);
  EXPECT_LT(r.bounce_rays, 64);
  EXPECT_GE(r.bounce_rays, 8);
  EXPECT_EQ(r.bounce_rays & (r.bounce_rays - 1), 0) << r.bounce_rays;
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 2000, ro.rays = 1024, ro.bounces = 2, ro.paths = 1024;
  const Reference ref = make_reference(mesh, scene, ro);
  const EvalResult e = evaluate(ref, vertex_positions(r.mesh), r.mesh.triangles, r.mesh.source_face, r.transfer);
  // eval's RMS holds its reference's own noise; without it, the asset's error.
  const double truth = std::sqrt(std::max(0.0, std::pow(e.rms_percent, 2) - std::pow(e.noise_floor_percent, 2)));
  std::printf("bounced: predicted %.3f%% (± %.3f), eval %.3f%% (floor %.3f); direct predicted %.3f%%\n", r.predicted.percent,
              r.predicted.standard_error, truth, e.noise_floor_percent, r.predicted_direct.percent);
  EXPECT_NEAR(r.predicted.percent, truth, 0.25 * truth);
  // The direct light's error alone, what the target was measured on before, misses what eval finds.
  EXPECT_GT(r.predicted.percent, r.predicted_direct.percent);
}

class BakeBounceTarget : public ::testing::TestWithParam<bool> {};

TEST_P(BakeBounceTarget, ATargetBelowTheBouncedErrorBuysMoreRays) {
  // A fine ground under a high half-plane (the first error target's scene), 4 rays per vertex
  // and pass: the light changes slowly, so noise is what is left, and a target 15% below the
  // first bake's error buys rays (bounce or direct) until it is met or a warning says why not;
  // the measured error falls and every ray is counted.
  const Mesh mesh = test::build(test::merge(test::grid(16, 0.3), test::quad(50, 0.4, false, 0.5)));
  BakeOptions o;
  o.transfer.rays = 4, o.vertex_share = 0, o.bounce.bounces = 2, o.target_error = 80;
  o.bounce.fit_samples = GetParam();  // without: the vertices' bounced values are the asset's, and bounce rays may be bought
  const BakeResult first = bake(mesh, o);
  o.target_error = 0.85 * first.predicted.percent;
  const BakeResult more = bake(mesh, o);
  std::printf("first %.3f%%, target %.3f%%: %.3f%% after %d bounce and %d direct rounds (bounce rays %d) %s\n", first.predicted.percent, o.target_error, more.predicted.percent, more.target_bounce_rounds, more.target_direct_rounds, more.bounce_rays, more.warnings.empty() ? "" : more.warnings.back().c_str());
  EXPECT_GE(more.target_bounce_rounds + more.target_direct_rounds, 1);
  if (more.target_bounce_rounds > 0) {
    EXPECT_GT(more.bounce_rays, 4);
  }
  EXPECT_TRUE(more.predicted.percent <= o.target_error || !more.warnings.empty());
  EXPECT_LT(more.predicted.percent, first.predicted.percent);
  EXPECT_GT(more.rays, first.rays);
  // Thread counts do not change the rounds.
  o.transfer.threads = 1;
  const BakeResult one = bake(mesh, o);
  EXPECT_EQ((one.transfer - more.transfer).cwiseAbs().maxCoeff(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutBouncedSamples, BakeBounceTarget, ::testing::Bool());

TEST(Bake, ABudgetBelowTheInputSimplifiesAndTheFitToTheSourceBeatsItsPointValues) {
  // A sphere resting on a plane: the contact shadow is what a simplified asset must keep.
  const Mesh mesh = test::build(test::merge(test::icosphere(3), test::transformed(test::grid(16), 5.0, Eigen::Vector3d(-2.5, -2.5, -1))));
  ASSERT_EQ(mesh.num_faces(), 1280u + 512u);
  BakeOptions o;
  o.refine = Refinement::Adaptive, o.adaptive.budget = 451;
  o.transfer.rays = 64, o.transfer.threads = 1;
  const BakeResult lsq = bake(mesh, o);
  EXPECT_TRUE(lsq.simplified);
  EXPECT_EQ(lsq.mesh.num_faces(), 451u);  // exact: the plane has a boundary
  EXPECT_TRUE(lsq.transfer.allFinite());
  EXPECT_EQ(lsq.transfer.rows(), static_cast<Eigen::Index>(lsq.mesh.num_vertices()));
  // As many samples on the input's surface as the fit would give the asset's faces (both ways
  // takes twice as many).
  EXPECT_NEAR(double(lsq.fit_data.samples.size()), o.samples.per_triangle * 451, 1.0);
  bool recorded = false;
  for (const auto& [k, v] : lsq.metadata) recorded |= k == "simplified";
  EXPECT_TRUE(recorded);
  o.transfer.threads = 2;
  EXPECT_EQ((bake(mesh, o).transfer - lsq.transfer).cwiseAbs().maxCoeff(), 0.0);  // any thread count
  // One reference judges all three: the fit against the traced vertex values, and the transfer
  // metric against the geometric one.
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 4000, ro.rays = 1024, ro.order = 4;
  const Reference ref = make_reference(mesh, scene, ro);
  auto error = [&](const BakeResult& r, const RowMatrixXd& v) {
    return evaluate_by_closest_point(ref, vertex_positions(r.mesh), r.mesh.triangles, v).rms_percent;
  };
  const double e_fit = error(lsq, lsq.transfer), e_point = error(lsq, lsq.point);
  EXPECT_LT(e_fit, 0.9 * e_point) << e_fit << "% against " << e_point << "%";
  // The bake predicts that error on samples held out of the input's surface: within three of
  // their standard errors, and a tenth of eval's figure for eval's own spread (4,000 points).
  EXPECT_GE(lsq.predicted.samples, 4096u);
  {  // spread by area, each stands for the same area (not its face's over its count: fewer samples than faces)
    const Holdout& h = lsq.fit_data.plan.holdout;
    double sum = 0;
    for (double w : h.weight) {
      EXPECT_EQ(w, h.weight.front());
      sum += w;
    }
    EXPECT_NEAR(sum, test::total_area(mesh), 1e-9 * test::total_area(mesh));
  }
  EXPECT_NEAR(lsq.predicted.percent, e_fit, 3 * lsq.predicted.standard_error + 0.1 * e_fit) << "± " << lsq.predicted.standard_error;
  o.simplify.metric = SimplifyMetric::Geometry;
  const BakeResult geometry = bake(mesh, o);
  const double e_geometry = error(geometry, geometry.transfer);
  EXPECT_LT(e_fit, e_geometry) << e_fit << "% against " << e_geometry << "%";
}

TEST(Bake, ASimplifiedMeshsSamplesGetHalfAVertexsRaysAndErrLess) {
  // The sphere on its plane brought to half: the fit's samples, which stand for the whole
  // input and are not weighed against the vertices by noise, get half a vertex's rays each
  // unless the count is given, and their lower noise shows in eval's error. Both ways does the
  // same below the input's count, and keeps the count at it.
  const Mesh mesh = test::build(test::merge(test::icosphere(3), test::transformed(test::grid(16), 5.0, Eigen::Vector3d(-2.5, -2.5, -1))));
  BakeOptions o;
  o.refine = Refinement::Adaptive, o.adaptive.budget = 900;
  o.transfer.rays = 128;
  const BakeResult half = bake(mesh, o);
  ASSERT_NEAR(double(half.fit_data.samples.size()), o.samples.per_triangle * double(half.mesh.num_faces()), 1.0);
  EXPECT_EQ(half.fit_data.sample_rays, 64);
  o.sample_rays_auto = false;  // --sample-rays given: that count
  const BakeResult fixed = bake(mesh, o);
  EXPECT_EQ(fixed.fit_data.sample_rays, o.sample_rays);
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 4000, ro.rays = 1024, ro.order = 4;
  const Reference ref = make_reference(mesh, scene, ro);
  auto error = [&](const BakeResult& r) { return evaluate_by_closest_point(ref, vertex_positions(r.mesh), r.mesh.triangles, r.transfer).rms_percent; };
  const double e_half = error(half), e_fixed = error(fixed);
  EXPECT_LT(e_half, 0.7 * e_fixed) << e_half << "% against " << e_fixed << "%";
  o.sample_rays_auto = true, o.refine = Refinement::Auto;
  const BakeResult below = bake(mesh, o);
  ASSERT_GT(below.refine.splits, 0u);
  EXPECT_EQ(below.fit_data.sample_rays, 64);
  o.adaptive.budget = mesh.num_faces();
  const BakeResult at = bake(mesh, o);
  ASSERT_GT(at.refine.splits, 0u);
  EXPECT_EQ(at.fit_data.sample_rays, o.sample_rays);
}

TEST(Bake, ASimplifiedAssetsHoldOutIsTracedAgainWhereItsNoiseBuriesTheError) {
  // Vertices traced at 512 rays err little; the hold-out's 32 rays a sample are noisy enough to
  // bury that error, so its samples are traced again, in whole passes, until the prediction's
  // standard error is a quarter of it (or the passes stop paying), and it still predicts eval.
  const Mesh mesh = test::build(test::merge(test::transformed(test::icosphere(3), 1.0, Eigen::Vector3d(0, 0, 0.5)),
                                            test::transformed(test::grid(4), 6.0, Eigen::Vector3d(-3, -3, -1))));
  BakeOptions o;
  o.transfer.rays = 512;
  o.refine = Refinement::Auto, o.adaptive.budget = mesh.num_faces();
  const BakeResult r = bake(mesh, o);
  const Holdout& held = r.fit_data.plan.holdout;
  ASSERT_GT(held.rays, o.pilot.rays);
  EXPECT_EQ(held.rays % o.pilot.rays, 0);
  EXPECT_EQ(r.holdout_sharpen_rays, uint64_t(held.rays - o.pilot.rays) * held.size());
  EXPECT_LE(r.predicted.standard_error, 0.25 * r.predicted.percent);
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 4000, ro.rays = 2048, ro.order = 4;
  std::vector<double> point_errors;
  const double e = evaluate_by_closest_point(make_reference(mesh, scene, ro), vertex_positions(r.mesh), r.mesh.triangles, r.transfer,
                                             0, &point_errors).rms_percent;
  EXPECT_NEAR(r.predicted.percent, e, 3 * r.predicted.standard_error + 0.1 * e) << "± " << r.predicted.standard_error;
  // Each point's error, as asked: one per reference point, whose RMS is eval's figure.
  ASSERT_EQ(point_errors.size(), ro.points);
  double s = 0;
  for (double x : point_errors) s += x * x;
  EXPECT_NEAR(100 * std::sqrt(s / double(point_errors.size())), e, 1e-9 * e);
}

// --refine auto: a finely tessellated sphere floating over a coarse floor. The sphere's transfer
// is smooth (collapse it), its shadow crosses the floor's few large faces (split them). Exactly
// the budget from below, at and above the input's count; at the input's own count a far lower
// error than its own triangles (asserted below half), one reference judging both.
TEST(Bake, BothWaysReachesAnyBudgetAndAtTheInputsCountBeatsItsTriangles) {
  const Mesh mesh = test::build(test::merge(test::transformed(test::icosphere(3), 1.0, Eigen::Vector3d(0, 0, 0.5)),
                                            test::transformed(test::grid(4), 6.0, Eigen::Vector3d(-3, -3, -1))));
  const size_t F = mesh.num_faces();
  ASSERT_EQ(F, 1280u + 32u);
  BakeOptions o;
  o.transfer.rays = 64, o.transfer.threads = 1;
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 4000, ro.rays = 1024, ro.order = 4;
  const Reference ref = make_reference(mesh, scene, ro);
  const BakeResult none = bake(mesh, o);
  const double e_none = evaluate(ref, vertex_positions(none.mesh), none.mesh.triangles, none.mesh.source_face, none.transfer).rms_percent;
  o.refine = Refinement::Auto;
  for (size_t T : {F / 2, F, 2 * F}) {
    o.adaptive.budget = T;
    // Away from the input's count only the count is checked: a quarter of the samples (under the
    // sanitizers, the samples cost most of this test's time).
    o.samples.per_triangle = T == F ? SampleOptions().per_triangle : 4;
    const BakeResult r = bake(mesh, o);
    EXPECT_EQ(r.mesh.num_faces(), T);  // exact: the floor has a boundary
    EXPECT_TRUE(r.simplified);
    EXPECT_GT(r.simplify.collapses, 0u);
    EXPECT_GT(r.refine.splits, 0u);
    EXPECT_TRUE(r.transfer.allFinite());
    // The fit samples the input's surface at twice the samples per triangle (kBothWaysSampleFactor),
    // by area: the count is the asset's faces times 32, to the nearest sample the draw rounds to.
    EXPECT_NEAR(double(r.fit_data.samples.size()), 2 * o.samples.per_triangle * double(T), 1.0);
    if (T != F) continue;
    const double e = evaluate_by_closest_point(ref, vertex_positions(r.mesh), r.mesh.triangles, r.transfer).rms_percent;
    EXPECT_LT(e, 0.5 * e_none) << e << "% against the input's triangles' " << e_none << "%";
    bool recorded = false;
    for (const auto& [k, v] : r.metadata) recorded |= k == "auto";
    EXPECT_TRUE(recorded);
    // α is chosen as the default bake's is, ascending from 0, on samples held out of the input.
    ASSERT_FALSE(r.alpha_trials.empty());
    EXPECT_EQ(r.alpha_trials.front().first, o.alpha_choices.front());
    // The last tried is kept, or the one before it (whose gain over it the hold-out could not tell).
    EXPECT_TRUE(r.alpha == r.alpha_trials.back().first || (r.alpha_trials.size() > 1 && r.alpha == r.alpha_trials[r.alpha_trials.size() - 2].first));
    // The same hold-out predicts the asset's error, as eval measures it.
    EXPECT_GE(r.predicted.samples, 4096u);
    // Within three of its standard errors, and a tenth of eval's figure for eval's own spread (4,000
    // points; its reference's noise, which the hold-out subtracts and eval does not, adds to it).
    EXPECT_NEAR(r.predicted.percent, e, 3 * r.predicted.standard_error + 0.1 * e) << "± " << r.predicted.standard_error;
    // Traced again where its standard error was above a quarter of it: whole passes over it.
    const Holdout& held = r.fit_data.plan.holdout;
    EXPECT_EQ(r.holdout_sharpen_rays, uint64_t(held.rays - o.pilot.rays) * held.size());
    // The second round of vertex rays: only the input's vertices, at most their own rays again.
    // Refinement's vertices, of both cycles (the second's collapses can take either kind), are
    // flagged; as many as the two passes made, less the second's collapses of them.
    ASSERT_EQ(r.refined_vertex.size(), r.mesh.num_vertices());
    EXPECT_EQ(r.auto_cycles, 1);
    EXPECT_GT(r.auto_cycle_collapses, 0u);
    size_t refined = 0;
    double before = 0, extra = 0;
    for (size_t i = 0; i < r.mesh.num_vertices(); ++i) {
      if (r.refined_vertex[i]) {
        EXPECT_EQ(r.vertex_rays[i], 64.0) << "new vertex " << i;
        ++refined;
      } else {
        before += 64, extra += r.vertex_rays[i] - 64;
      }
    }
    EXPECT_GT(refined, 0u);
    EXPECT_LE(refined, r.refine.new_vertices);
    EXPECT_GT(r.top_up.rays, 0u);
    EXPECT_EQ(extra, double(r.top_up.rays));
    EXPECT_LE(extra, before);
    // The variants below check what differs, not the fit's accuracy: a quarter of the samples
    // each (under the sanitizers, the samples cost most of this test's time).
    {
      BakeOptions fixed = o;
      fixed.alpha_auto = false, fixed.vertex_share = 0, fixed.samples.per_triangle = 4;
      const BakeResult f = bake(mesh, fixed);
      EXPECT_TRUE(f.alpha_trials.empty());
      EXPECT_EQ(f.alpha, o.fit.alpha);
      EXPECT_EQ(f.top_up.rays, 0u);
      const double ef = evaluate_by_closest_point(ref, vertex_positions(f.mesh), f.mesh.triangles, f.transfer).rms_percent;
      EXPECT_LT(ef, 0.5 * e_none);
    }
    for (int cycles : {0, 2}) {
      BakeOptions c = o;
      c.auto_cycles = cycles, c.samples.per_triangle = 4;
      const BakeResult b = bake(mesh, c);
      const double ec = evaluate_by_closest_point(ref, vertex_positions(b.mesh), b.mesh.triangles, b.transfer).rms_percent;
      EXPECT_EQ(b.auto_cycles, cycles);
      EXPECT_EQ(b.mesh.num_faces(), T);
      EXPECT_LT(ec, 0.5 * e_none) << cycles << " further cycles";
      size_t flagged = 0;
      for (char f : b.refined_vertex) flagged += f != 0;
      if (cycles == 0) EXPECT_EQ(flagged, b.refine.new_vertices);  // nothing collapsed after refining
      else EXPECT_GT(b.auto_cycle_collapses, r.auto_cycle_collapses);
    }
    {
      // Smaller cycles: each collapses 3% of the budget (two faces a collapse, one on a boundary),
      // so two of them fewer times than one of a tenth.
      BakeOptions c = o;
      c.auto_cycles = 2, c.auto_cycle_share = 0.03, c.samples.per_triangle = 4;
      const BakeResult b = bake(mesh, c);
      EXPECT_EQ(b.auto_cycles, 2);
      EXPECT_EQ(b.mesh.num_faces(), T);
      EXPECT_GT(b.auto_cycle_collapses, 0u);
      EXPECT_LE(double(b.auto_cycle_collapses), 2 * (0.03 * double(T)));
      EXPECT_LT(b.auto_cycle_collapses, r.auto_cycle_collapses);
      c.auto_cycle_share = 0.6;
      EXPECT_THROW(bake(mesh, c), InputError);
    }
    o.transfer.threads = 2;
    EXPECT_EQ((bake(mesh, o).transfer - r.transfer).cwiseAbs().maxCoeff(), 0.0) << "any thread count";
    o.transfer.threads = 1;
  }
}

TEST(Bake, EarlyStopDoublesWhereTheSphereMeetsThePlaneAndStopsOnTheOpenTop) {
  // A sphere on a plane, up to 512 rays from 32: the sphere's top sees the whole sky, exact after
  // the first round. Its pole stops there; the rest of the top doubles only while a face around
  // it sees the plane (the guard against a lucky first round), and stays exact. The plane's
  // vertices, which see the sphere, double. Every count is 32·2^j, the bake's rays are their sum
  // (point fit: no samples, no top-up), the metadata says how it was traced, and the result does
  // not depend on threads.
  const Mesh mesh = test::build(test::merge(test::icosphere(2), test::quad(2.5, -1.0, true)));
  BakeOptions o;
  o.fit.method = FitMethod::Point;
  o.transfer.rays = 512, o.round_rays = 32, o.transfer.threads = 1;
  const BakeResult one = bake(mesh, o);
  ASSERT_EQ(one.vertex_rays.size(), mesh.num_vertices());
  double sum = 0;
  size_t upper = 0, at_first = 0, plane_doubled = 0;
  for (uint32_t i = 0; i < mesh.num_vertices(); ++i) {
    const double R = one.vertex_rays[i], j = std::log2(R / 32);
    EXPECT_EQ(j, std::round(j)) << i;
    EXPECT_LE(R, 512.0);
    sum += R;
    const Eigen::Vector3d p = mesh.point(i);
    if (p.z() > 0.8) {
      ++upper, at_first += R == 32;
      EXPECT_EQ(one.point_variance[i], 0.0) << p.transpose();
    }
    if (p.z() > 0.999) {
      EXPECT_EQ(R, 32.0) << "the pole";
    }
    if (p.z() < -0.99) plane_doubled += R > 32;
  }
  EXPECT_GT(upper, 10u);
  EXPECT_GT(at_first, 0u);
  EXPECT_GT(plane_doubled, 0u);
  EXPECT_EQ(static_cast<double>(one.rays), sum);
  EXPECT_LT(sum, 0.95 * 512 * double(mesh.num_vertices()));
  bool recorded = false;
  for (const auto& [k, v] : one.metadata) recorded |= k == "early_stop";
  EXPECT_TRUE(recorded);
  o.transfer.threads = 2;
  const BakeResult two = bake(mesh, o);
  EXPECT_EQ(two.transfer, one.transfer);
  EXPECT_EQ(two.vertex_rays, one.vertex_rays);
  o.round_rays = 31;
  EXPECT_THROW(bake(mesh, o), InputError);
}

TEST(Bake, WithEarlyStopThePilotJudgesInterpolationAsIfEveryVertexHadItsRays) {
  // The fit's pilot sends samples where interpolation fails, judged against the corners' noise.
  // Early stop leaves some vertices noisier; judged at their own noise, the contact shadow's faces
  // would look like noise and go unsampled. The pilot sees each vertex's variance at --rays, so
  // it samples about the faces it samples when every vertex traces them, while the bake traces
  // fewer rays.
  const Mesh mesh = test::build(test::merge(test::icosphere(3), test::transformed(test::grid(8), 5.0, Eigen::Vector3d(-2.5, -2.5, -1.0))));
  BakeOptions o;
  o.transfer.rays = 1024;
  const BakeResult fixed = bake(mesh, o);
  o.round_rays = 32, o.stop_noise_percent = 4;
  const BakeResult early = bake(mesh, o);
  std::printf("sampled faces: fixed %zu, early stop %zu; vertex rays %.0f against %.0f\n", fixed.fit_data.plan.sampled_faces,
              early.fit_data.plan.sampled_faces, std::accumulate(early.vertex_rays.begin(), early.vertex_rays.end(), 0.0),
              std::accumulate(fixed.vertex_rays.begin(), fixed.vertex_rays.end(), 0.0));
  ASSERT_GT(fixed.fit_data.plan.sampled_faces, 20u);
  // Measured: 0.94 of fixed's faces; judged at each vertex's own noise, 0.88.
  EXPECT_GE(double(early.fit_data.plan.sampled_faces), 0.92 * double(fixed.fit_data.plan.sampled_faces));
  EXPECT_LT(early.rays, fixed.rays);
}

TEST(Bake, AmbientOcclusionIsOrderOneAndClamped) {
  BakeOptions o;
  o.signal = AssetSignal::Ao;
  o.transfer.order = 6;  // ignored: AO is order-1 transfer
  o.transfer.rays = 16;
  const BakeResult r = bake(sphere_on_plane(), o);
  ASSERT_EQ(r.transfer.cols(), 1);
  EXPECT_GE(r.transfer.minCoeff(), 0.0);
  EXPECT_LE(r.transfer.maxCoeff() * kAoPerT0, 1.0 + 1e-12);
}

TEST(Bake, BadOptionsNameTheValueNotAFlag) {
  const Mesh mesh = sphere_on_plane();
  auto message = [&](const BakeOptions& o) {
    try {
      bake(mesh, o);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  BakeOptions adaptive;
  adaptive.refine = Refinement::Adaptive;
  EXPECT_EQ(message(adaptive), "adaptive refinement needs a triangle budget");
  BakeOptions rays;
  rays.sample_rays = 0;
  EXPECT_EQ(message(rays), "rays per sample must be between 1 and 1048576, got 0");
  BakeOptions order;
  order.transfer.order = 11;
  EXPECT_EQ(message(order), "SH order must be between 1 and 10, got 11");
  BakeOptions levels;
  levels.refine = Refinement::Uniform, levels.uniform.levels = 9;
  EXPECT_EQ(message(levels), "uniform refinement: levels must be between 1 and 8, got 9");
  EXPECT_THROW(parse_refinement("sideways"), InputError);
  EXPECT_EQ(parse_refinement("uniform"), Refinement::Uniform);
  EXPECT_STREQ(refinement_name(Refinement::Adaptive), "adaptive");
}

}  // namespace
}  // namespace prtsub
