#include <gtest/gtest.h>

#include "cli/pipeline.h"
#include "helpers.h"
#include "prt/evaluate.h"
#include "prt/refine_signal.h"
#include "prt/sh.h"
#include "subdiv/exceptions.h"
#include "subdiv/uniform.h"

namespace prtsub {
namespace {

double area_of(const Mesh& m) {
  double a = 0;
  for (const Triangle& t : m.triangles) a += triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2]));
  return a;
}

TEST(Uniform, LinearSplitKeepsTheSurfaceAndCarriesSourceFaces) {
  Mesh m = test::build(test::icosphere(1));
  Mesh u = refine_uniform(m, UniformOptions{2, UniformScheme::Linear, 60});
  EXPECT_EQ(u.num_faces(), 80u * 16);
  EXPECT_NEAR(area_of(u), area_of(m), 1e-12 * area_of(m));
  std::vector<Triangle> pos(u.num_faces());
  for (size_t f = 0; f < pos.size(); ++f)
    for (int k = 0; k < 3; ++k) pos[f][k] = u.vertex_position[u.triangles[f][k]];
  EXPECT_EQ(count_edges(pos).boundary, 0u);
  // Every refined face lies inside its source face: its centroid is in that face's plane.
  for (size_t f = 0; f < u.num_faces(); ++f) {
    const Triangle& s = m.triangles[u.source_face[f]];
    Eigen::Vector3d a = m.point(s[0]), n = (m.point(s[1]) - a).cross(m.point(s[2]) - a).normalized();
    Eigen::Vector3d c = (u.point(u.triangles[f][0]) + u.point(u.triangles[f][1]) + u.point(u.triangles[f][2])) / 3;
    EXPECT_NEAR(n.dot(c - a), 0, 1e-12);
  }
}

TEST(Uniform, CreasesRefinePerSideAndLoopSmooths) {
  Mesh cube = test::build(test::cube(), 60);
  Mesh u = refine_uniform(cube, UniformOptions{2, UniformScheme::Linear, 60});
  EXPECT_EQ(u.num_faces(), 12u * 16);
  for (const Triangle& t : u.triangles) {
    Eigen::Vector3d fn = (u.point(t[1]) - u.point(t[0])).cross(u.point(t[2]) - u.point(t[0])).normalized();
    for (uint32_t c : t) EXPECT_NEAR(fn.dot(u.normals.row(c)), 1.0, 1e-9);
  }
  Mesh sphere = test::build(test::icosphere(1));
  Mesh loop = refine_uniform(sphere, UniformOptions{1, UniformScheme::Loop, 60});
  EXPECT_EQ(loop.num_faces(), 320u);
  double moved = 0;
  for (Eigen::Index p = 0; p < loop.positions.rows(); ++p) moved = std::max(moved, std::abs(loop.positions.row(p).norm() - 1));
  EXPECT_GT(moved, 1e-3);  // Loop pulls midpoints off the flat faces
}

TEST(Uniform, UvsAreInterpolatedPerSideOfASeam) {
  const Mesh m = build_mesh(parse_obj(test::seam_square_obj(), "seam.obj"), "seam.obj");
  const Mesh u = refine_uniform(m, UniformOptions{2, UniformScheme::Linear, 60});
  ASSERT_EQ(static_cast<size_t>(u.uv.rows()), u.num_vertices());
  for (size_t f = 0; f < u.num_faces(); ++f)
    for (uint32_t c : u.triangles[f])
      EXPECT_LT((u.uv.row(c).transpose() - test::seam_uv(int(u.source_face[f]), u.point(c))).norm(), 1e-12);
  // Loop moves positions, not UVs: they are still each side's linear interpolation, so they stay
  // inside the hull of the side's input UVs.
  const Mesh loop = refine_uniform(m, UniformOptions{1, UniformScheme::Loop, 60});
  ASSERT_EQ(static_cast<size_t>(loop.uv.rows()), loop.num_vertices());
  EXPECT_TRUE(loop.uv.allFinite());
  EXPECT_GE(loop.uv.minCoeff(), 0.0);
  EXPECT_LE(loop.uv.maxCoeff(), 1.0);
  EXPECT_GT(loop.num_vertices(), static_cast<size_t>(loop.positions.rows()));  // the seam survives
}

TEST(Estimates, ClosedForms) {
  double a[2] = {3, 4}, b[2] = {0, 0}, c[2] = {3, 4};
  EdgeView e{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 1, 0), a, b, 2};
  RayScene scene(test::build(test::cube()).positions, position_triangles(test::build(test::cube())));
  auto err = [&](EdgeEstimate est, const EdgeView& v) {
    TransferSignalOptions o;
    o.estimate = est;
    o.curvature_guard_deg = 10;
    return TransferSignal(scene, o).edge_error(v);
  };
  EXPECT_DOUBLE_EQ(err(EdgeEstimate::Shadow, e), 5.0);
  EXPECT_DOUBLE_EQ(err(EdgeEstimate::Length, e), 10.0);
  EXPECT_DOUBLE_EQ(err(EdgeEstimate::Probe, e), 10.0);
  EXPECT_DOUBLE_EQ(err(EdgeEstimate::Root, e), 5.0 * std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(err(EdgeEstimate::Relative, e), 5.0 / 2.5);
  EXPECT_NEAR(err(EdgeEstimate::Curvature, e), 5.0 / (M_PI / 2), 1e-12);
  EdgeView flat = e;
  flat.nb = flat.na;
  EXPECT_NEAR(err(EdgeEstimate::Curvature, flat), 5.0 / (10 * M_PI / 180), 1e-12);  // the guard
  EdgeView same = e;
  same.vb = c;
  for (EdgeEstimate est : {EdgeEstimate::Relative, EdgeEstimate::Shadow, EdgeEstimate::Curvature, EdgeEstimate::Length,
                           EdgeEstimate::Probe, EdgeEstimate::Root})
    EXPECT_EQ(err(est, same), 0.0);
  EXPECT_EQ(parse_estimate("root"), EdgeEstimate::Root);
  EXPECT_STREQ(estimate_name(EdgeEstimate::Root), "root");
  EXPECT_THROW(parse_estimate("best"), InputError);
}

TEST(Estimates, ProbesSeeShadowsTheCornersMissAndRootWeighsThemByAreaToTheQuarter) {
  // A floor at z = -1 and a small occluder just above its centre, facing down: the probe at
  // the centre is dark while the corners (all lit, value c) say nothing changes.
  Mesh m = test::build(test::merge(test::quad(2.0, -1.0, true), test::quad(0.3, -0.9, false)));
  RayScene scene(m.positions, position_triangles(m));
  TransferSignalOptions o;
  o.transfer.rays = 256;
  const RowMatrixXd lit = unshadowed_transfer(4, Eigen::Vector3d::UnitZ()).transpose();
  const double area = 8.0;  // each half of the 4×4 floor
  std::vector<FaceProbe> faces{{Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitZ(), area, lit.data(), lit.data(), lit.data(), 16},
                               {Eigen::Vector3d(1.9, 1.9, -1), Eigen::Vector3d::UnitZ(), area, lit.data(), lit.data(), lit.data(), 16}};
  std::vector<double> probe, root;
  o.estimate = EdgeEstimate::Probe;
  TransferSignal(scene, o).probe_faces(faces, probe);
  o.estimate = EdgeEstimate::Root;
  TransferSignal(scene, o).probe_faces(faces, root);
  ASSERT_EQ(probe.size(), 2u);
  ASSERT_EQ(root.size(), 2u);
  EXPECT_GT(probe[0], 0.5 * lit.norm() * std::sqrt(3 * area));  // most of the sky is blocked
  EXPECT_LT(probe[1], 0.1 * probe[0]);                               // the far corner sees the sky
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(root[i] * std::pow(3 * area, 0.25), probe[i], 1e-12 * probe[0]);
  o.estimate = EdgeEstimate::Length;  // no probes
  std::vector<double> none{1.0};
  TransferSignal(scene, o).probe_faces(faces, none);
  EXPECT_TRUE(none.empty());
}

TEST(Eval, FlatUnoccludedSurfaceHasZeroErrorAndReferencePointsAreFixed) {
  test::TempDir dir;
  test::write_obj(dir.path("plane.obj"), test::quad(1.0, 0.0, true));
  Mesh src = load_mesh(dir.path("plane.obj"));
  RayScene scene(src.positions, position_triangles(src));
  ReferenceOptions ro;
  ro.points = 500, ro.rays = 64, ro.order = 4, ro.noise_points = 100;
  Reference ref = make_reference(src, scene, ro);
  Reference again = make_reference(src, scene, ro);
  EXPECT_EQ(ref.points, again.points);
  TransferOptions to;
  to.rays = 4;
  RowMatrixXd t = shadowed_transfer(scene, vertex_positions(src), src.normals, to);
  EvalResult e = evaluate(ref, vertex_positions(src), src.triangles, src.source_face, t);
  EXPECT_EQ(e.points, 500u);
  EXPECT_LT(e.rms_percent, 1e-10);   // constant transfer, exactly interpolated
  EXPECT_LT(e.noise_floor_percent, 1e-10);  // unoccluded: the reference is exact
  EXPECT_NEAR(unshadowed_norm(1), M_PI * 0.5 / std::sqrt(M_PI), 1e-15);  // Â_0 y_00
}

TEST(Eval, RefinementLowersErrorAndAdaptiveBeatsUniformOnAContactShadow) {
  // The generated scene: a coarse icosphere resting on a two-triangle plane.
  test::TempDir dir;
  const std::string src = dir.path("scene.obj");
  test::write_obj(src, test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  Mesh mesh = load_mesh(src);
  RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 4000, ro.rays = 1024, ro.noise_points = 500;
  Reference ref = make_reference(mesh, scene, ro);
  auto error_of = [&](BakeSettings s) {
    s.input = src;
    s.transfer.rays = 128;
    BakeResult r = run_bake(s);
    return evaluate(ref, vertex_positions(r.mesh), r.mesh.triangles, r.mesh.source_face, r.transfer).rms_percent;
  };
  BakeSettings none, u2, u3, adaptive;
  u2.refine = u3.refine = "uniform";
  u2.uniform.levels = 2, u3.uniform.levels = 3;
  const size_t level3 = mesh.num_faces() * 64;
  adaptive.refine = "adaptive", adaptive.budget = level3;
  const double e0 = error_of(none), e2 = error_of(u2), e3 = error_of(u3), ea = error_of(adaptive);
  EXPECT_LT(e2, e0);
  EXPECT_LT(e3, e2);
  EXPECT_LT(ea, e3) << "adaptive " << ea << "% vs uniform " << e3 << "% at " << level3 << " triangles";
  EXPECT_GT(e3 - ea, 3 * ref.noise_floor * 100);  // adaptive's lead is well above the reference's noise
}

TEST(Bake, AdaptiveRefinementIsIdenticalForAnyThreadCount) {
  test::TempDir dir;
  const std::string src = dir.path("scene.obj");
  test::write_obj(src, test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  BakeSettings s;
  s.input = src, s.refine = "adaptive", s.budget = 900, s.batch = 16;
  s.transfer.rays = 32, s.transfer.threads = 1;
  BakeResult one = run_bake(s);
  s.transfer.threads = 2;
  BakeResult two = run_bake(s);
  EXPECT_EQ(one.mesh.triangles, two.mesh.triangles);
  EXPECT_EQ((one.transfer - two.transfer).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(one.mesh.num_faces(), 900u);
}

}  // namespace
}  // namespace prtsub
