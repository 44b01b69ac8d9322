#include "prtsub/prt/sample_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "helpers.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

// An 8×8 ground grid facing up, optionally under a half-plane at height 0.15 over x > 0.45:
// the transfer changes fastest under the occluder's edge, over a width like the cell size.
struct Ground {
  Mesh mesh, world;  // the ground, and the ground with its occluder
  RayScene scene;
  RowMatrixXd prior;
  std::vector<double> variance;
  explicit Ground(bool occluded, int rays = 256)
      : mesh(test::build(test::grid(8, 0.3))),
        world(occluded ? test::build(test::merge(test::grid(8, 0.3), test::quad(50, 0.15, false, 0.45))) : mesh),
        scene(world.positions, position_triangles(world)) {
    TransferOptions o;
    o.rays = rays;
    const RowMatrixX3d offsets = vertex_offset_directions(mesh);
    prior = shadowed_transfer(scene, vertex_positions(mesh), mesh.normals, o, nullptr, {}, &offsets, &variance);
  }
};

TransferOptions pilot_rays(int threads = 0) {
  TransferOptions o;
  o.seed = 11, o.threads = threads;
  return o;
}

SamplePlan plan(const Ground& g, const PilotOptions& o = {}, int threads = 0) {
  return plan_samples(g.mesh, g.scene, make_pilot_samples(g.mesh, o, 5), g.prior, g.variance, pilot_rays(threads), o);
}

TEST(SamplePlan, AnOpenPlaneNeedsNoSamples) {
  // Every point sees the whole hemisphere: the transfer is exact everywhere (the control
  // variate), so interpolation reproduces it and no face may be sampled.
  const Ground g(false);
  const SamplePlan p = plan(g);
  EXPECT_EQ(p.sampled_faces, 0u);
  EXPECT_EQ(*std::max_element(p.face_weight.begin(), p.face_weight.end()), 0.0);
  EXPECT_GE(p.pilot_drawn, PilotOptions{}.min_samples);
  EXPECT_EQ(p.pilot_samples, p.pilot_drawn / 2);  // two stages: nothing needs the second
  EXPECT_EQ(p.rays, uint64_t(PilotOptions{}.rays) * p.pilot_samples);
}

TEST(SamplePlan, WhereOnlyTheUnshadowedCurvatureDiffersNoFaceNeedsSamples) {
  // A coarse sphere traced in a scene without it (nothing to hit, not even its own facets, which
  // would shade a point whose interpolated normal tilts from its face's): every value is exactly
  // t_u(n), yet t_u curves across each face, which the plain test calls interpolation error. With
  // the fit projecting t_u exactly, the pilot tests what is left after it: nothing here.
  const Mesh m = test::build(test::icosphere(1));
  const Mesh far = test::build(test::transformed(test::cube(), 0.01, Eigen::Vector3d(100, 100, 100)));
  const RayScene scene(far.positions, position_triangles(far));
  TransferOptions o;
  o.rays = 64;
  std::vector<double> variance;
  const RowMatrixX3d offsets = vertex_offset_directions(m);
  const RowMatrixXd prior = shadowed_transfer(scene, vertex_positions(m), m.normals, o, nullptr, {}, &offsets, &variance);
  PilotOptions plain, exact;
  exact.exact_unshadowed = true;
  const SamplePlan a = plan_samples(m, scene, make_pilot_samples(m, plain, 5), prior, variance, pilot_rays(), plain);
  const SamplePlan b = plan_samples(m, scene, make_pilot_samples(m, exact, 5), prior, variance, pilot_rays(), exact);
  EXPECT_GT(a.sampled_faces, m.num_faces() / 2);
  EXPECT_EQ(b.sampled_faces, 0u);
}

TEST(SamplePlan, FacesWhereInterpolationFailsAreSampledTheOthersNot) {
  const Ground g(true);
  const SamplePlan p = plan(g);
  // The truth, independently: each face's interpolation error at its centroid, from 8192-ray
  // transfer at the centroid and at the corners.
  const Mesh& m = g.mesh;
  const size_t F = m.num_faces();
  RowMatrixX3d centroid(Eigen::Index(F), 3), normal(Eigen::Index(F), 3);
  for (size_t f = 0; f < F; ++f) {
    const Triangle& t = m.triangles[f];
    centroid.row(Eigen::Index(f)) = ((m.point(t[0]) + m.point(t[1]) + m.point(t[2])) / 3).transpose();
    normal.row(Eigen::Index(f)) << 0, 0, 1;
  }
  TransferOptions ref;
  ref.rays = 8192, ref.seed = 99;
  const RowMatrixX3d offsets = vertex_offset_directions(m);
  const RowMatrixXd at_corners = shadowed_transfer(g.scene, vertex_positions(m), m.normals, ref, nullptr, {}, &offsets);
  const RowMatrixXd at_centroids = shadowed_transfer(g.scene, centroid, normal, ref);
  std::vector<double> error(F);
  for (size_t f = 0; f < F; ++f) {
    const Triangle& t = m.triangles[f];
    error[f] = (at_centroids.row(Eigen::Index(f)) - (at_corners.row(t[0]) + at_corners.row(t[1]) + at_corners.row(t[2])) / 3).norm();
  }
  std::vector<double> sorted = error;
  std::sort(sorted.begin(), sorted.end());
  const double top = sorted[F * 9 / 10], low = sorted[F / 4];
  size_t low_sampled = 0, low_count = 0;
  for (size_t f = 0; f < F; ++f) {
    if (error[f] >= top) {
      EXPECT_GT(p.face_weight[f], 0.0) << "face " << f << " error " << error[f];
    }
    if (error[f] <= low) low_count++, low_sampled += p.face_weight[f] > 0;
  }
  // The quarter that interpolation reproduces best is mostly left to it, and the plan does
  // leave faces out (the test is not passed by sampling everything).
  EXPECT_LE(low_sampled, low_count / 4) << low_sampled << " of " << low_count;
  EXPECT_LT(p.sampled_faces, F * 3 / 4);
  EXPECT_GT(p.sampled_faces, F / 10);
  // Among the sampled faces, the density follows the error: the worst decile's mean weight
  // is above the mean weight of the others.
  double top_w = 0, rest_w = 0;
  size_t top_n = 0, rest_n = 0;
  for (size_t f = 0; f < F; ++f) {
    if (p.face_weight[f] == 0) continue;
    if (error[f] >= top) top_w += p.face_weight[f], ++top_n;
    else rest_w += p.face_weight[f], ++rest_n;
  }
  ASSERT_GT(top_n * rest_n, 0u);
  EXPECT_GT(top_w / double(top_n), 1.2 * rest_w / double(rest_n));
}

TEST(SamplePlan, TwoStagesTraceTheRestOnlyWhereTheFirstCouldNotClearAFace) {
  // Half the pilot first: on the open plane nothing is left to trace; under the occluder's edge
  // the faces the one-stage plan samples for their error are still found, and no sample is
  // traced twice (a sample's rays are its own whichever stage traces it).
  PilotOptions two, whole;
  two.first_share = 0.5, whole.first_share = 1;
  const Ground open(false);
  const size_t drawn = make_pilot_samples(open.mesh, two, 5).size();
  const SamplePlan open_plan = plan(open, two);
  EXPECT_EQ(open_plan.sampled_faces, 0u);
  EXPECT_EQ(open_plan.pilot_samples, drawn / 2);
  EXPECT_EQ(open_plan.rays, uint64_t(two.rays) * open_plan.pilot_samples);
  EXPECT_EQ(open_plan.holdout.size(), open_plan.pilot_samples);  // under the hold-out cap: all of the first stage

  const Ground g(true);
  const SamplePlan one = plan(g, whole), staged = plan(g, two), staged2 = plan(g, two, 2);
  EXPECT_EQ(one.pilot_samples, drawn);
  EXPECT_EQ(staged.face_weight, staged2.face_weight);  // any thread count
  EXPECT_LT(staged.pilot_samples, drawn);
  EXPECT_GT(staged.pilot_samples, drawn / 2);
  EXPECT_EQ(staged.rays, uint64_t(two.rays) * staged.pilot_samples);
  size_t both = 0, only_one = 0;
  for (size_t f = 0; f < one.face_weight.size(); ++f) {
    both += one.face_weight[f] > 0 && staged.face_weight[f] > 0;
    only_one += one.face_weight[f] > 0 && staged.face_weight[f] == 0;
  }
  EXPECT_GT(both, 0u);
  EXPECT_LE(only_one, one.sampled_faces / 10) << only_one << " of " << one.sampled_faces;
  EXPECT_EQ(staged.pilot_drawn, drawn);
}

TEST(SamplePlan, TheScreenWeighsTheInterpolationErrorAgainstTheVerticesNoise) {
  // The open plane's transfer is exact at any ray count and the same at every point, so with
  // every vertex value off by δ and given a variance σ², each screened sample's excess is exactly
  // ‖δ‖² − σ²Σh² and its vertex noise σ²Σh² (h its barycentrics): the ratio is
  // ‖δ‖²·Σw / (σ²·Σw·Σh²) − 1 in closed form.
  Ground g(false);
  const double sigma2 = 1e-4;
  Eigen::RowVectorXd delta = Eigen::RowVectorXd::Zero(g.prior.cols());
  delta[0] = 0.0048, delta[2] = -0.0064;  // ‖δ‖² = 6.4e-5, against an interpolated noise near σ²/2
  RowMatrixXd prior = g.prior.rowwise() + delta;
  const std::vector<double> variance(g.variance.size(), sigma2);
  PilotOptions o;
  const SurfaceSamples pilot = make_pilot_samples(g.mesh, o, 5);
  const SamplePlan p = plan_samples(g.mesh, g.scene, pilot, prior, variance, pilot_rays(), o);
  ASSERT_TRUE(p.screened_out) << p.screen_ratio << " +- " << p.screen_standard_error;
  EXPECT_EQ(p.sampled_faces, 0u);
  EXPECT_EQ(*std::max_element(p.face_weight.begin(), p.face_weight.end()), 0.0);
  EXPECT_EQ(p.pilot_drawn, pilot.size());
  EXPECT_EQ(p.pilot_samples, p.screen_samples);  // the rest of the pilot is not traced
  EXPECT_EQ(p.rays, uint64_t(o.rays) * p.screen_samples);
  ASSERT_EQ(p.holdout.size(), p.screen_samples);  // the screen's samples are the hold-out
  double w = 0, wh2 = 0;
  for (size_t j = 0; j < p.holdout.size(); ++j) {
    w += p.holdout.weight[j];
    wh2 += p.holdout.weight[j] * p.holdout.barycentric.row(static_cast<Eigen::Index>(j)).squaredNorm();
  }
  const double expected = delta.squaredNorm() * w / (sigma2 * wh2) - 1;
  EXPECT_NEAR(p.screen_ratio, expected, 1e-9);
  EXPECT_GT(p.screen_ratio, 0);
  EXPECT_LT(p.screen_ratio + p.screen_standard_error, 1);

  // Four times the error: the ratio is above 1 and the pilot goes on, finding every face off.
  prior = g.prior.rowwise() + 2 * delta;
  const SamplePlan on = plan_samples(g.mesh, g.scene, pilot, prior, variance, pilot_rays(), o);
  EXPECT_FALSE(on.screened_out);
  EXPECT_NEAR(on.screen_ratio, 4 * (expected + 1) - 1, 1e-9);
  EXPECT_EQ(on.sampled_faces, g.mesh.num_faces());
  // With no noise to weigh it against, nothing is screened out, whatever the ratio asked for.
  o.screen_ratio = 1e6;
  EXPECT_FALSE(plan_samples(g.mesh, g.scene, pilot, g.prior, g.variance, pilot_rays(), o).screened_out);
}

TEST(SamplePlan, AScreenThatLetsThePilotGoOnChangesNothingOfItsPlan) {
  // Each pilot sample's rays are its own, whichever pass traces it: a screen that does not stop
  // the pilot leaves the faces, the hold-out and the rays exactly as without one.
  const Ground g(true);
  PilotOptions off;
  off.screen_ratio = 0;
  const SamplePlan with = plan(g), without = plan(g, off);
  EXPECT_FALSE(with.screened_out);
  EXPECT_GT(with.screen_samples, 0u);
  EXPECT_GT(with.screen_ratio, 1);  // a shadow edge across the faces
  EXPECT_EQ(without.screen_samples, 0u);
  EXPECT_GT(with.sampled_faces, 0u);
  EXPECT_EQ(with.face_weight, without.face_weight);
  EXPECT_EQ(with.pilot_samples, without.pilot_samples);
  EXPECT_EQ(with.rays, without.rays);
  ASSERT_EQ(with.holdout.size(), without.holdout.size());
  EXPECT_EQ(with.holdout.values, without.holdout.values);
  EXPECT_EQ(with.holdout.face, without.holdout.face);
}

TEST(SamplePlan, TheSameForAnyThreadCountAndRejectsWhatItCannotUse) {
  const Ground g(true);
  const SamplePlan one = plan(g, {}, 1);
  const SamplePlan two = plan(g, {}, 2);
  EXPECT_EQ(one.face_weight, two.face_weight);
  PilotOptions single;
  single.rays = 1;  // no variance from one ray
  EXPECT_THROW(plan(g, single), InputError);
  EXPECT_THROW(plan_samples(g.mesh, g.scene, make_pilot_samples(g.mesh, {}, 5), g.prior.topRows(3), g.variance, pilot_rays(), {}),
               InputError);
  PilotOptions bad;
  bad.area_share = 2;
  EXPECT_THROW(plan(g, bad), InputError);
  bad = PilotOptions{};
  bad.per_triangle = 0;
  EXPECT_THROW(plan(g, bad), InputError);
  EXPECT_EQ(parse_sample_allocation("pilot"), SampleAllocation::Pilot);
  EXPECT_THROW(parse_sample_allocation("everywhere"), InputError);
}

TEST(SampleRays, TheChoiceHasTheLeastModelledMomentErrorAtTheBudget) {
  // With B rays per face, Q rays per sample give n = B/Q samples and an error of
  // variation/n² + noise(Q)/n: the closed form, candidate by candidate.
  SampleRaysChoice c;
  c.choices = {4, 16, 32}, c.noise = {0.4, 0.04, 0.011};
  c.variation = 0.11;
  choose_sample_rays(c, 256);
  ASSERT_EQ(c.cost.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    const double n = 256.0 / c.choices[k];
    EXPECT_DOUBLE_EQ(c.cost[k], 0.11 / (n * n) + c.noise[k] / n);
  }
  EXPECT_EQ(c.rays, 16);  // 4: 0.0067 + 0.025; 16: 0.0069 + 0.0025; 32: 0.0138 + 0.0014
  // A variation that dwarfs the noise (a shadow across large faces): the most samples.
  c.variation = 50;
  choose_sample_rays(c, 256);
  EXPECT_EQ(c.rays, 4);
  // No variation: the least noise per ray, noise(Q)·Q, here 32's (0.352 against 0.64 and 1.6).
  c.variation = 0;
  choose_sample_rays(c, 256);
  EXPECT_EQ(c.rays, 32);
  // A negative measured excess is noise about zero: as zero.
  c.variation = -1;
  choose_sample_rays(c, 256);
  EXPECT_EQ(c.rays, 32);
  // The variation's share falls as 1/n², the noise's as 1/n: a small budget buys samples, a large one rays.
  c.variation = 1;
  choose_sample_rays(c, 64);  // 4: 1/256 + 0.4/16; 16: 1/16 + 0.04/4
  EXPECT_EQ(c.rays, 4);
  c.variation = 0.11;
  choose_sample_rays(c, 4096);
  EXPECT_EQ(c.rays, 32);
  // Given a count, the choice leaves it only for a modelled error below `keep` (0.8) of its own.
  c.noise = {0.4, 0.04, 0.011};
  c.variation = 0;
  choose_sample_rays(c, 256, 16);  // 32 at 0.55 of 16's: moves
  EXPECT_EQ(c.rays, 32);
  choose_sample_rays(c, 256, 16, 0.5);
  EXPECT_EQ(c.rays, 16);
  choose_sample_rays(c, 256, 8);  // not a candidate: the least
  EXPECT_EQ(c.rays, 32);
  SampleRaysChoice bad = c;
  bad.noise.pop_back();
  EXPECT_THROW(choose_sample_rays(bad, 256), InputError);
  EXPECT_THROW(choose_sample_rays(c, 0), InputError);
  SampleRaysChoice none;
  EXPECT_THROW(choose_sample_rays(none, 256), InputError);
}

TEST(SampleRays, ThePilotMeasuresEachCandidatesNoiseAndTheSampledFacesVariation) {
  const Ground g(true);
  PilotOptions o;
  o.sample_ray_choices = {4, 16};
  const SamplePlan p = plan(g, o), p2 = plan(g, o, 2);
  const SampleRaysChoice& c = p.sample_rays;
  ASSERT_EQ(c.noise.size(), 2u);
  EXPECT_EQ(c.rays, 0);  // the pilot measures; the budget's owner chooses
  EXPECT_GT(c.points, 100u);
  EXPECT_LE(c.points, o.noise_points);
  EXPECT_EQ(c.rays_traced, 2 * uint64_t(4 + 16) * c.points);
  EXPECT_EQ(p.rays, uint64_t(o.rays) * p.pilot_samples + c.rays_traced);
  EXPECT_GT(c.variation, 0.0);
  EXPECT_EQ(c.noise, p2.sample_rays.noise);  // any thread count
  EXPECT_EQ(c.variation, p2.sample_rays.variation);
  EXPECT_EQ(p.face_weight, plan(g).face_weight);  // measuring changes nothing of the plan
  // Independently: at every pilot point on a sampled face, the variance over 8 seeds, weighted
  // by the face's weight as the measurement is. The measurement averages about c.points
  // squared differences, heavy-tailed; 20% is several of its standard errors here.
  const SurfaceSamples pilot = make_pilot_samples(g.mesh, o, 5);
  std::vector<size_t> on;
  for (size_t k = 0; k < pilot.size(); ++k)
    if (p.face_weight[pilot.face[k]] > 0) on.push_back(k);
  const auto n = Eigen::Index(on.size());
  RowMatrixX3d points(n, 3), normals(n, 3), offsets(n, 3);
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto k = Eigen::Index(on[size_t(j)]);
    points.row(j) = pilot.points.row(k), normals.row(j) = pilot.normals.row(k), offsets.row(j) = pilot.offsets.row(k);
  }
  for (size_t q = 0; q < 2; ++q) {
    const int seeds = 8;
    std::vector<RowMatrixXd> runs;
    for (int s = 0; s < seeds; ++s) {
      TransferOptions t;
      t.rays = o.sample_ray_choices[q], t.seed = 1000 + uint64_t(s);
      runs.push_back(shadowed_transfer(g.scene, points, normals, t, nullptr, {}, &offsets));
    }
    double sum = 0, w = 0;
    for (Eigen::Index j = 0; j < n; ++j) {
      RowMatrixXd mean = RowMatrixXd::Zero(1, runs[0].cols());
      for (const RowMatrixXd& r : runs) mean += r.row(j);
      mean /= seeds;
      double v = 0;
      for (const RowMatrixXd& r : runs) v += (r.row(j) - mean).squaredNorm();
      const double fw = p.face_weight[pilot.face[on[size_t(j)]]];
      sum += fw * v / (seeds - 1), w += fw;
    }
    const double truth = sum / w;
    std::printf("Q %d: measured %.5g, over 8 seeds %.5g\n", o.sample_ray_choices[q], c.noise[q], truth);
    EXPECT_NEAR(c.noise[q] / truth, 1.0, 0.2) << "Q " << o.sample_ray_choices[q] << ": " << c.noise[q] << " against " << truth;
  }
  EXPECT_GT(c.noise[0], 4 * c.noise[1]);
  // No candidates, or an open plane (nothing sampled): nothing measured.
  EXPECT_TRUE(plan(g).sample_rays.noise.empty());
  EXPECT_TRUE(plan(Ground(false), o).sample_rays.noise.empty());
  PilotOptions zero = o;
  zero.sample_ray_choices = {0, 16};
  EXPECT_THROW(plan(g, zero), InputError);
}

}  // namespace
}  // namespace prtsub
