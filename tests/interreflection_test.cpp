// Interreflection against closed forms: a white furnace (albedo 1, constant light, a bowl whose
// rays only ever hit its inside) converges to the light's own radiance, geometrically; a closed
// room lit by nothing stays black; back faces are black; and the result is the same for any
// thread count and with or without the hit cache.
#include "prtsub/prt/interreflection.h"

#include <gtest/gtest.h>

#include <cmath>

#include "helpers.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

Mesh bowl() { return test::build(test::bowl(3)); }

double mean_t0_error(const Mesh& mesh, const RowMatrixXd& t) {
  const double want = std::sqrt(M_PI) / 2;  // t0 of an unoccluded point: radiance 1 under light 1 at albedo 1
  double e = 0;
  for (Eigen::Index v = 0; v < t.rows(); ++v) e += std::abs(t(v, 0) - want);
  return e / static_cast<double>(mesh.num_vertices());
}

TEST(Interreflection, AWhiteFurnaceConvergesGeometricallyToTheLightsRadiance) {
  const Mesh mesh = bowl();
  const RayScene scene(mesh.positions, position_triangles(mesh));
  TransferOptions t;
  t.order = 2, t.rays = 1024;
  const RowMatrixXd direct = shadowed_transfer(scene, vertex_positions(mesh), mesh.normals, t);
  std::vector<double> error;
  for (int k = 0; k <= 8; ++k) {
    BounceOptions b;
    b.bounces = k, b.albedo = 1, b.rays = 1024;
    error.push_back(mean_t0_error(mesh, interreflected_transfer(mesh, scene, direct, b)));
  }
  // A bowl that is half a sphere blocks about half of each point's cosine-weighted rays, so each
  // bounce takes about that share of what is left: the errors fall by a steady ratio below 1.
  for (int k = 1; k <= 4; ++k) {
    const double ratio = error[static_cast<size_t>(k)] / error[static_cast<size_t>(k - 1)];
    EXPECT_GT(ratio, 0.3) << k;
    EXPECT_LT(ratio, 0.7) << k;
  }
  EXPECT_GT(error[0], 0.25);   // direct light alone: far from the furnace's answer
  EXPECT_LT(error[8], 0.012);  // eight bounces: within the rays' noise of it (1024 rays, 1% of t0)
}

TEST(Interreflection, AClosedRoomLitByNothingStaysBlackAfterAnyBounces) {
  // The unit cube wound inwards: a room with no opening. Every ray is blocked, so the direct
  // transfer is the estimator's zero, and bouncing zero gives zero at any albedo.
  const Mesh mesh = test::build(test::closed_room(), 0);
  const RayScene scene(mesh.positions, position_triangles(mesh));
  TransferOptions t;
  t.order = 3, t.rays = 64;
  const RowMatrixX3d offsets = vertex_offset_directions(mesh);  // as bake starts its rays: into the corners
  const RowMatrixXd direct = shadowed_transfer(scene, vertex_positions(mesh), mesh.normals, t, nullptr, {}, &offsets);
  const double direct_max = direct.cwiseAbs().maxCoeff();
  for (double albedo : {0.0, 0.5, 1.0})
    for (int bounces : {1, 4, 16}) {
      BounceOptions b;
      b.bounces = bounces, b.albedo = albedo, b.rays = 64;
      const RowMatrixXd total = interreflected_transfer(mesh, scene, direct, b);
      EXPECT_EQ(total.cwiseAbs().maxCoeff(), 0.0) << albedo << " " << bounces;
    }
  EXPECT_EQ(direct_max, 0.0) << "every ray of a closed room is blocked";
}

TEST(Interreflection, BackFacesAreBlack) {
  // A ground, and a plate above it: facing down, the ground sees its front and receives its
  // light; facing up, the ground sees its back and receives nothing.
  for (const bool plate_up : {true, false}) {
    const Mesh mesh = test::build(test::merge(test::quad(2.0, 0.0, true), test::quad(1.0, 0.5, plate_up)));
    const RayScene scene(mesh.positions, position_triangles(mesh));
    TransferOptions t;
    t.order = 2, t.rays = 128;
    const RowMatrixXd direct = shadowed_transfer(scene, vertex_positions(mesh), mesh.normals, t);
    BounceOptions b;
    b.bounces = 1, b.albedo = 0.8, b.rays = 128;
    const RowMatrixXd added = interreflected_transfer(mesh, scene, direct, b) - direct;
    double ground = 0;
    for (size_t v = 0; v < mesh.num_vertices(); ++v)
      if (std::abs(mesh.point(static_cast<uint32_t>(v)).z()) < 1e-9) ground += added.row(static_cast<Eigen::Index>(v)).cwiseAbs().sum();
    if (plate_up) EXPECT_EQ(ground, 0.0);
    else EXPECT_GT(ground, 0.0);
  }
}

TEST(Interreflection, IsTheSameForAnyThreadCountWithOrWithoutTheCache) {
  const Mesh mesh = test::build(test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  BakeOptions o;
  o.transfer.rays = 32, o.transfer.threads = 1, o.fit.method = FitMethod::Point;
  o.bounce.bounces = 3, o.bounce.cache = BounceCache::On;
  const BakeResult one = bake(mesh, o);
  o.transfer.threads = 2, o.bounce.cache = BounceCache::Off;
  const BakeResult two = bake(mesh, o);
  EXPECT_TRUE(one.bounce.cached);
  EXPECT_FALSE(two.bounce.cached);
  EXPECT_EQ(one.bounce.rays * 3, two.bounce.rays) << "without the cache each pass traces again";
  EXPECT_EQ((one.transfer - two.transfer).cwiseAbs().maxCoeff(), 0.0);
  o.bounce.bounces = 0;
  const BakeResult none = bake(mesh, o);
  EXPECT_GT((one.transfer - none.transfer).col(0).minCoeff(), -1e-12) << "bounces only add light";
  EXPECT_GT((one.transfer - none.transfer).col(0).maxCoeff(), 0.01);
  o.signal = AssetSignal::Ao, o.bounce.bounces = 1;
  EXPECT_THROW(bake(mesh, o), InputError);
}

TEST(Interreflection, AGatherAtTheVerticesIsTheirPassAndBeforeLastIsOnePassLess) {
  const Mesh mesh = test::build(test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  const RayScene scene(mesh.positions, position_triangles(mesh));
  TransferOptions t;
  t.order = 3, t.rays = 64;
  const RowMatrixX3d offsets = vertex_offset_directions(mesh), points = vertex_positions(mesh);
  const RowMatrixXd direct = shadowed_transfer(scene, points, mesh.normals, t, nullptr, {}, &offsets);
  BounceOptions b;
  b.rays = 64, b.bounces = 1;
  // The same rays (each vertex's stream of the same seed) from the same points: the same sums.
  const RowMatrixXd pass = interreflected_transfer(mesh, scene, direct, b) - direct;
  EXPECT_GT(pass.col(0).maxCoeff(), 0.01);
  EXPECT_LT((gather_bounce(mesh, scene, direct, points, mesh.normals, offsets, b) - pass).cwiseAbs().maxCoeff(), 1e-15);
  RowMatrixXd before_last;
  b.bounces = 3;
  interreflected_transfer(mesh, scene, direct, b, nullptr, &before_last);
  b.bounces = 2;
  EXPECT_EQ((before_last - interreflected_transfer(mesh, scene, direct, b)).cwiseAbs().maxCoeff(), 0.0);
  RowMatrixX3d two(2, 3);
  two.setZero();
  EXPECT_THROW(gather_bounce(mesh, scene, direct, points, mesh.normals, two, b), InputError);
}

TEST(Interreflection, TheFitSeesBouncedLightUnlessAskedNotTo) {
  // The fit's samples gather one bounce and the fit runs again (its effect on error is measured
  // on real scenes: scenes_test.cpp, ScenesBounceFit); here, that it runs, and only when asked.
  const Mesh mesh = test::build(test::merge(test::icosphere(2), test::quad(3.0, -1.05, true)));
  BakeOptions o;
  o.transfer.rays = 32, o.transfer.order = 2, o.bounce.bounces = 2;
  const BakeResult samples = bake(mesh, o);
  o.bounce.fit_samples = false;
  const BakeResult vertices = bake(mesh, o);
  EXPECT_EQ(samples.bounce.sample_rays, uint64_t(samples.fit_data.sample_rays) * samples.fit_data.samples.size());
  EXPECT_EQ(vertices.bounce.sample_rays, 0u);
  EXPECT_GT((samples.transfer - vertices.transfer).cwiseAbs().maxCoeff(), 1e-3);
  o.fit.method = FitMethod::Point, o.bounce.fit_samples = true;
  EXPECT_EQ(bake(mesh, o).bounce.sample_rays, 0u) << "no samples, nothing to gather at";
}

TEST(Interreflection, RefinementKeyedOnBouncedLightKeepsTheDirectTransferForThePasses) {
  // --bounce-rekey: half the budget on direct light, the rest keyed on direct plus bounced. The
  // point values the passes then bounce are direct transfer: the input's vertices trace exactly
  // what a bake without the re-key traces, and the asset is the passes applied to them.
  const Mesh mesh = test::build(test::merge(test::quad(2.0, 0.0, true), test::quad(1.0, 0.5, false)));
  BakeOptions o;
  o.transfer.order = 2, o.transfer.rays = 64;
  o.refine = Refinement::Adaptive, o.adaptive.budget = 200;
  o.bounce.bounces = 2;
  o.fit.method = FitMethod::Point;
  o.rekey_share = 0.5;
  const BakeResult keyed = bake(mesh, o);
  o.rekey_share = 0;
  const BakeResult plain = bake(mesh, o);
  EXPECT_EQ(keyed.mesh.num_faces(), 200u);
  const auto V = static_cast<Eigen::Index>(mesh.num_vertices());
  EXPECT_EQ((keyed.point.topRows(V) - plain.point.topRows(V)).cwiseAbs().maxCoeff(), 0.0);
  const RayScene scene(keyed.mesh.positions, position_triangles(keyed.mesh));
  BounceOptions b = resolve_bake_options(o).bounce;
  const RowMatrixXd again = interreflected_transfer(keyed.mesh, scene, keyed.point, b);
  EXPECT_LT((again - keyed.transfer).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((keyed.transfer - keyed.point).cwiseAbs().maxCoeff(), 0.01);  // the plate lights the ground
  // Without the re-key too: the passes read the refined mesh's own triangles (the scene the bake
  // traced its direct light in holds the input's, whose face numbers mean other triangles now).
  const RayScene plain_scene(plain.mesh.positions, position_triangles(plain.mesh));
  EXPECT_LT((interreflected_transfer(plain.mesh, plain_scene, plain.point, b) - plain.transfer).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Interreflection, ASimplifiedMeshBouncesOnItsOwnTriangles) {
  // Simplified below the input's count, the asset has fewer triangles than the input scene: a
  // bounce must never read a face number of the input's in the asset's list.
  const Mesh mesh = test::build(test::merge(test::icosphere(2), test::quad(3.0, -1.0, true)));
  BakeOptions o;
  o.transfer.order = 2, o.transfer.rays = 32;
  o.refine = Refinement::Adaptive, o.adaptive.budget = 120;
  o.bounce.bounces = 1;
  o.fit.method = FitMethod::Point;
  const BakeResult r = bake(mesh, o);
  ASSERT_LT(r.mesh.num_faces(), mesh.num_faces());
  const RayScene scene(r.mesh.positions, position_triangles(r.mesh));
  const RowMatrixXd again = interreflected_transfer(r.mesh, scene, r.point, resolve_bake_options(o).bounce);
  EXPECT_LT((again - r.transfer).cwiseAbs().maxCoeff(), 1e-12);
}

}  // namespace
}  // namespace prtsub
