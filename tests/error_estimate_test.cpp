#include "prtsub/prt/error_estimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "helpers.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"

namespace prtsub {
namespace {

// A hold-out set on a jittered grid: n samples spread by area (the pilot's), with "traced"
// values f(p) plus seeded Gaussian noise of variance `noise` (summed over K = 4 values),
// which the set also reports.
struct HeldOut {
  Mesh mesh = test::build(test::grid(6, 0.5));
  Holdout h;
  HeldOut(const std::function<Eigen::Vector4d(const Eigen::Vector3d&)>& f, double noise, size_t per_face) {
    Rng rng(17, 0);
    // Sized once: growing the matrices a row at a time copies them each time, which under
    // AddressSanitizer (no in-place realloc) made each test take 105 s instead of 0.05.
    const Eigen::Index n = Eigen::Index(mesh.num_faces() * per_face);
    h.barycentric.resize(n, 3);
    h.values.resize(n, 4);
    Eigen::Index row = 0;
    for (uint32_t face = 0; face < mesh.num_faces(); ++face) {
      const Triangle& t = mesh.triangles[face];
      const double area = triangle_area(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]));
      for (size_t k = 0; k < per_face; ++k) {
        double u = rng.uniform(), v = rng.uniform();
        if (u + v > 1) u = 1 - u, v = 1 - v;
        const Eigen::Vector3d b(1 - u - v, u, v);
        const Eigen::Vector3d p = b[0] * mesh.point(t[0]) + b[1] * mesh.point(t[1]) + b[2] * mesh.point(t[2]);
        Eigen::Vector4d value = f(p);
        for (int q = 0; q < 4; ++q) {  // Box–Muller
          const double g = std::sqrt(-2 * std::log(1 - rng.uniform())) * std::cos(2 * M_PI * rng.uniform());
          value[q] += std::sqrt(noise / 4) * g;
        }
        h.face.push_back(face), h.weight.push_back(area / double(per_face)), h.variance.push_back(noise);
        h.barycentric.row(row) = b.transpose();
        h.values.row(row) = value.transpose().cast<float>();
        ++row;
      }
    }
  }
};

Eigen::Vector4d linear(const Eigen::Vector3d& p) { return Eigen::Vector4d(0.9, 0.3 * p.x(), -0.2 * p.y(), 0.1); }

RowMatrixXd at_vertices(const Mesh& m, const std::function<Eigen::Vector4d(const Eigen::Vector3d&)>& f) {
  RowMatrixXd x(Eigen::Index(m.num_vertices()), 4);
  for (uint32_t i = 0; i < m.num_vertices(); ++i) x.row(i) = f(m.point(i)).transpose();
  return x;
}

TEST(HoldoutError, ExactValuesHaveNoErrorAndAnOffsetIsMeasuredExactly) {
  const HeldOut s(linear, 0.0, 20);
  const RowMatrixXd exact = at_vertices(s.mesh, linear);
  const ErrorEstimate zero = holdout_error(s.mesh, s.h, exact);
  EXPECT_NEAR(zero.percent, 0.0, 1e-4);  // float storage of the values
  EXPECT_EQ(zero.samples, s.h.size());
  // Every vertex off by δ in each of 4 values: ‖f − g‖ = 2δ everywhere, in units of ‖t_unshadowed‖ (order 2).
  RowMatrixXd off = exact;
  off.array() += 0.01;
  EXPECT_NEAR(holdout_error(s.mesh, s.h, off).percent, 100 * 0.02 / unshadowed_norm(2), 1e-4);
}

TEST(HoldoutError, NoiseInTheHeldOutValuesIsRemovedAndInterpolationErrorIsNot) {
  // A quadratic signal interpolated linearly: the true error from an independent quadrature of
  // the interpolation error; the held-out values carry noise 25× its square, which the
  // estimate must take out to within its own standard error.
  const auto quad = [](const Eigen::Vector3d& p) {
    return Eigen::Vector4d(0.9 + 3 * p.x() * p.x(), 0.3 * p.x(), -2 * p.y() * p.y(), 0.1 + p.x() * p.y());
  };
  const double noise = 0.01;
  const HeldOut s(quad, noise, 400);
  const RowMatrixXd x = at_vertices(s.mesh, quad);
  // Truth: the area-weighted mean of ‖f − g‖² on a fine midpoint rule per face.
  double truth = 0, area = 0;
  const int n = 40;
  for (const Triangle& t : s.mesh.triangles) {
    const double a = triangle_area(s.mesh.point(t[0]), s.mesh.point(t[1]), s.mesh.point(t[2]));
    double sum = 0;
    int count = 0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        const Eigen::Vector3d b((i + 1.0 / 3) / n, (j + 1.0 / 3) / n, 1 - (i + j + 2.0 / 3) / n);
        const Eigen::Vector3d p = b[0] * s.mesh.point(t[0]) + b[1] * s.mesh.point(t[1]) + b[2] * s.mesh.point(t[2]);
        const Eigen::Vector4d g = b[0] * x.row(t[0]).transpose() + b[1] * x.row(t[1]).transpose() + b[2] * x.row(t[2]).transpose();
        sum += (quad(p) - g).squaredNorm(), ++count;
      }
    truth += a * sum / count, area += a;
  }
  const double truth_percent = 100 * std::sqrt(truth / area) / unshadowed_norm(2);
  ASSERT_LT(truth / area, noise / 10);  // the noise dwarfs what is measured
  const ErrorEstimate e = holdout_error(s.mesh, s.h, x);
  EXPECT_GT(e.standard_error, 0.0);
  EXPECT_NEAR(e.percent, truth_percent, 4 * e.standard_error) << "truth " << truth_percent;
  EXPECT_LT(e.standard_error, 0.2 * truth_percent);  // and the test has teeth
  // Without the noise taken out it would be far off: the raw mean square is noise-dominated.
  EXPECT_GT(100 * std::sqrt(noise) / unshadowed_norm(2), 3 * truth_percent);
}

TEST(HoldoutError, APairedDifferenceSeesWhatEitherErrorsNoiseHides) {
  // Exact values a, and b off by δ in each of 4 values (‖Δ‖² = 4δ² everywhere): b's squared error
  // is 4δ² above a's. The held-out values carry noise far larger, which each error's own standard
  // error reflects; paired on the same samples, each one's noise cancels but for 2e·Δ.
  const double noise = 0.01, delta = 0.003;
  const HeldOut s(linear, noise, 400);
  const RowMatrixXd a = at_vertices(s.mesh, linear);
  RowMatrixXd b = a;
  b.array() += delta;
  const ErrorDifference d = holdout_difference(s.mesh, s.h, a, b);
  EXPECT_NEAR(d.mean, -4 * delta * delta, 3 * d.standard_error);
  EXPECT_LT(d.mean + 2 * d.standard_error, 0.0);  // told apart at two standard errors
  const ErrorDifference back = holdout_difference(s.mesh, s.h, b, a);
  EXPECT_DOUBLE_EQ(back.mean, -d.mean);
  EXPECT_DOUBLE_EQ(back.standard_error, d.standard_error);
  // Unpaired, each E²'s own standard error (δE² = 2E·δE, unit²) is far wider: per sample the
  // noise spreads ‖e‖² by noise/√2 and the paired term 2e·Δ by 2δ√noise, √noise/(2√2δ) ≈ 12 times
  // less (less with the samples' unequal weights; with no pairing it would be 0.7 times).
  const ErrorEstimate eb = holdout_error(s.mesh, s.h, b);
  const double unit = unshadowed_norm(2) / 100;
  const double unpaired = 2 * (eb.percent * unit) * (eb.standard_error * unit);
  EXPECT_LT(5 * d.standard_error, unpaired);
  EXPECT_THROW(holdout_difference(s.mesh, s.h, a, RowMatrixXd::Zero(3, 4)), InputError);
}

TEST(HoldoutError, EmptyOrMismatchedSets) {
  const HeldOut s(linear, 0.0, 2);
  EXPECT_EQ(holdout_error(s.mesh, Holdout{}, at_vertices(s.mesh, linear)).samples, 0u);
  EXPECT_THROW(holdout_error(s.mesh, s.h, RowMatrixXd::Zero(3, 4)), InputError);
  EXPECT_THROW(holdout_error(s.mesh, s.h, RowMatrixXd::Zero(Eigen::Index(s.mesh.num_vertices()), 9)), InputError);
}

TEST(HoldoutError, RgbValuesAreJudgedAsTheRmsOverTheirChannels) {
  // Three blocks of the same values: the same error as one; one block off by δ: a third of its square.
  const HeldOut s(linear, 0.0, 20);
  RowMatrixXd off = at_vertices(s.mesh, linear);
  off.array() += 0.01;
  Holdout rgb = s.h;
  rgb.values = s.h.values.replicate(1, 3).eval();
  const double one = holdout_error(s.mesh, s.h, off).percent;
  EXPECT_NEAR(holdout_error(s.mesh, rgb, off.replicate(1, 3)).percent, one, 1e-9);
  RowMatrixXd first_only = at_vertices(s.mesh, linear).replicate(1, 3);
  first_only.leftCols(4).array() += 0.01;
  EXPECT_NEAR(holdout_error(s.mesh, rgb, first_only).percent, one / std::sqrt(3.0), 1e-4);
  EXPECT_THROW(holdout_error(s.mesh, rgb, RowMatrixXd::Zero(Eigen::Index(s.mesh.num_vertices()), 8)), InputError);
}

TEST(HoldoutError, ASubsetKeepsEveryKthSampleWithItsWeightValueAndVariance) {
  const HeldOut s(linear, 0.01, 7);
  const size_t n = s.h.size();
  const Holdout sub = holdout_subset(s.h, n / 3);
  const size_t stride = (n + n / 3 - 1) / (n / 3);
  ASSERT_EQ(sub.size(), (n + stride - 1) / stride);
  EXPECT_LE(sub.size(), n / 3);
  for (size_t j = 0; j < sub.size(); ++j) {
    const size_t k = j * stride;
    EXPECT_EQ(sub.face[j], s.h.face[k]);
    EXPECT_EQ(sub.weight[j], s.h.weight[k]);
    EXPECT_EQ(sub.variance[j], s.h.variance[k]);
    EXPECT_EQ(sub.barycentric.row(Eigen::Index(j)), s.h.barycentric.row(Eigen::Index(k)));
    EXPECT_EQ(sub.values.row(Eigen::Index(j)), s.h.values.row(Eigen::Index(k)));
  }
  EXPECT_EQ(holdout_subset(s.h, n).size(), n);
  EXPECT_EQ(holdout_subset(s.h, 0).size(), n);
  EXPECT_EQ(sub.rays, s.h.rays);
}

// A ground grid under a half-plane occluder (a shadow edge across it), its vertex values, and a
// pilot whose hold-out is every one of its samples in order, traced at 8 rays (no screen, one
// stage), so row k of the hold-out is the pilot's sample k.
struct Shadowed {
  Mesh mesh = test::build(test::grid(8, 0.3));
  Mesh world = test::build(test::merge(test::grid(8, 0.3), test::quad(50, 0.15, false, 0.45)));
  RayScene scene{world.positions, position_triangles(world)};
  SurfaceSamples pilot;
  Holdout h;
  RowMatrixXd values;
  Shadowed() {
    TransferOptions o;
    o.rays = 16, o.order = 2, o.seed = 3;
    std::vector<double> variance;
    const RowMatrixX3d offsets = vertex_offset_directions(mesh);
    values = shadowed_transfer(scene, vertex_positions(mesh), mesh.normals, o, nullptr, {}, &offsets, &variance);
    PilotOptions po;
    po.rays = 8, po.screen_ratio = 0, po.first_share = 1, po.per_triangle = 40, po.holdout = 1 << 20;
    pilot = make_pilot_samples(mesh, po, 5);
    o.seed = 11;
    h = plan_samples(mesh, scene, pilot, values, variance, o, po).holdout;
  }
};

TEST(SharpenHoldout, TracesEachSampleAgainWhereThePilotDidAndMergesTheTwoByRays) {
  const Shadowed s;
  ASSERT_EQ(s.h.size(), s.pilot.size());
  ASSERT_EQ(s.h.rays, 8);
  TransferOptions more;
  more.rays = 24, more.order = 2, more.seed = 99;
  TransferStats stats;
  const Holdout out = sharpen_holdout(s.mesh, s.scene, s.h, more, &stats);
  EXPECT_EQ(out.rays, 32);
  EXPECT_EQ(stats.rays, 24 * s.h.size());
  // The same rays, traced independently at the pilot's own points, normals and offsets.
  std::vector<double> variance;
  const RowMatrixXd direct = shadowed_transfer(s.scene, s.pilot.points, s.pilot.normals, more, nullptr, {}, &s.pilot.offsets, &variance);
  double changed = 0;
  for (Eigen::Index k = 0; k < Eigen::Index(s.h.size()); ++k) {
    const auto i = size_t(k);
    const Eigen::RowVectorXd want = 0.25 * s.h.values.row(k).cast<double>() + 0.75 * direct.row(k);
    EXPECT_LT((out.values.row(k).cast<double>() - want).cwiseAbs().maxCoeff(), 1e-6) << k;
    EXPECT_NEAR(out.variance[i], s.h.variance[i] / 16 + 9 * variance[i] / 16, 1e-12 + 1e-6 * out.variance[i]) << k;
    EXPECT_EQ(out.face[i], s.h.face[i]);
    EXPECT_EQ(out.weight[i], s.h.weight[i]);
    changed = std::max(changed, (out.values.row(k) - s.h.values.row(k)).cwiseAbs().maxCoeff() * 1.0);
  }
  EXPECT_GT(changed, 1e-3);  // under the shadow edge the two estimates differ
}

TEST(SharpenHoldout, AtPointsTheCallerKeepsItTracesThemAsAtTheMeshsOwn) {
  // A simplified asset's hold-out lies on its source, not on the asset: the caller keeps the
  // points. Given the pilot's own, the result is the one sharpen_holdout finds on the mesh.
  const Shadowed s;
  TransferOptions more;
  more.rays = 24, more.order = 2, more.seed = 99;
  TransferStats on_mesh, at_points;
  const Holdout a = sharpen_holdout(s.mesh, s.scene, s.h, more, &on_mesh);
  const Holdout b = sharpen_holdout_at(s.pilot.points, s.pilot.normals, s.pilot.offsets, s.scene, s.h, more, &at_points);
  EXPECT_EQ(b.rays, 32);
  EXPECT_EQ(at_points.rays, on_mesh.rays);
  EXPECT_EQ(b.values, a.values);
  EXPECT_EQ(b.variance, a.variance);
  EXPECT_EQ(b.face, a.face);
  const RowMatrixX3d fewer = s.pilot.points.topRows(s.pilot.points.rows() - 1);
  EXPECT_THROW(sharpen_holdout_at(fewer, s.pilot.normals, s.pilot.offsets, s.scene, s.h, more), InputError);
}

TEST(SharpenHoldout, TheErrorsStandardErrorFallsAndItsMeanStaysWithinItsNoise) {
  const Shadowed s;
  const ErrorEstimate before = holdout_error(s.mesh, s.h, s.values);
  TransferOptions more;
  more.order = 2;
  more.rays = 56, more.seed = 99;
  const Holdout h64 = sharpen_holdout(s.mesh, s.scene, s.h, more);
  more.rays = 2040, more.seed = 123;
  const Holdout h2048 = sharpen_holdout(s.mesh, s.scene, s.h, more);
  const ErrorEstimate at64 = holdout_error(s.mesh, h64, s.values), reference = holdout_error(s.mesh, h2048, s.values);
  std::printf("hold-out error at 8 rays %.3f%% +- %.3f%%, at 64 %.3f%% +- %.3f%%, at 2048 %.3f%% +- %.3f%%\n", before.percent,
              before.standard_error, at64.percent, at64.standard_error, reference.percent, reference.standard_error);
  // Noise-dominated terms: the spread falls about as 1/rays (8x here), at least halved.
  EXPECT_LT(at64.standard_error, 0.5 * before.standard_error);
  // Each unbiased: within three (combined) standard errors of the 2048-ray estimate.
  EXPECT_NEAR(at64.percent, reference.percent, 3 * std::hypot(at64.standard_error, reference.standard_error));
  EXPECT_NEAR(before.percent, reference.percent, 3 * std::hypot(before.standard_error, reference.standard_error));
}

TEST(SharpenHoldout, RefusesBouncedValuesAnotherOrderAndNoRays) {
  const Shadowed s;
  TransferOptions more;
  more.order = 2, more.rays = 8;
  Holdout bounced = s.h;
  bounced.rays = 0;
  EXPECT_THROW(sharpen_holdout(s.mesh, s.scene, bounced, more), InputError);
  more.order = 3;
  EXPECT_THROW(sharpen_holdout(s.mesh, s.scene, s.h, more), InputError);
  more.order = 2, more.rays = 0;
  EXPECT_THROW(sharpen_holdout(s.mesh, s.scene, s.h, more), InputError);
  Holdout elsewhere = s.h;
  elsewhere.face[0] = uint32_t(s.mesh.num_faces());
  more.rays = 8;
  EXPECT_THROW(sharpen_holdout(s.mesh, s.scene, elsewhere, more), InputError);
}

}  // namespace
}  // namespace prtsub
