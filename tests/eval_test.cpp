#include "prtsub/prt/evaluate.h"

#include <gtest/gtest.h>

#include "helpers.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/closest_point.h"
#include "prtsub/prt/refine_signal.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

TEST(Estimates, ClosedForms) {
  double a[2] = {3, 4}, b[2] = {0, 0}, c[2] = {3, 4};
  EdgeView e{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 1, 0), a, b, 2};
  // The formulas alone: no ray scene, no transfer.
  auto err = [](EdgeEstimate est, const EdgeView& v) { return edge_estimate(est, v, 10); };
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
  EXPECT_NEAR(edge_estimate(EdgeEstimate::Curvature, flat, 20), 5.0 / (20 * M_PI / 180), 1e-12);
  // A probe: its distance from the corners' mean, in the unit of the edges' estimate.
  const double corner[2] = {0, 0}, probed[2] = {3, 4};
  const FaceProbe face{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 12.0, corner, corner, corner, 2};
  EXPECT_DOUBLE_EQ(probe_estimate(EdgeEstimate::Probe, face, probed), 5.0 * 6.0);  // √(3·12) = 6
  EXPECT_DOUBLE_EQ(probe_estimate(EdgeEstimate::Root, face, probed), 5.0 * std::sqrt(6.0));
  EXPECT_EQ(probe_estimate(EdgeEstimate::Length, face, probed), 0.0);
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

// A vertex of a mesh that only lies near the scene's surface (a coarse sphere's edge midpoint,
// inside a fine sphere) is traced at its closest point on the scene's mesh: there a lone convex
// surface sees the whole sky, and the control variate makes that exact, the unshadowed transfer
// of the interpolated normal. Unprojected, its rays start inside the fine sphere and are blocked.
TEST(Eval, ASignalProjectingOntoTheSourceTracesNewVerticesOnItsSurface) {
  const Mesh fine = test::build(test::icosphere(4));
  const RayScene scene(fine.positions, position_triangles(fine));
  const Mesh coarse = test::build(test::icosphere(0));
  const Triangle& t = coarse.triangles[0];
  NewVertex v;
  v.index = 0, v.a = t[0], v.b = t[1], v.position_index = 0;
  v.position = 0.5 * (coarse.point(t[0]) + coarse.point(t[1]));
  v.normal = v.position.normalized();
  ASSERT_LT(v.position.norm(), 0.9);  // well inside the fine sphere
  TransferSignalOptions o;
  o.transfer.rays = 64, o.transfer.order = 4;
  RowMatrixXd inside, projected;
  TransferSignal(scene, o).compute_values({v}, RowMatrixXd::Zero(1, 16), inside);
  o.project_onto = &fine;
  TransferSignal(scene, o).compute_values({v}, RowMatrixXd::Zero(1, 16), projected);
  const std::vector<SurfaceLocation> at = closest_points(fine, v.position.transpose());
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int c = 0; c < 3; ++c) n += at[0].barycentric[c] * fine.normals.row(fine.triangles[at[0].face][c]).transpose();
  const Eigen::VectorXd open = unshadowed_transfer(4, n.normalized());
  EXPECT_LT((projected.row(0).transpose() - open).norm(), 1e-12 * open.norm());
  EXPECT_LT(inside.row(0).norm(), 0.1 * open.norm()) << "unprojected, the sphere blocks it";
}

TEST(Eval, ProjectingOntoASurfaceMovesPointsWithItsNormalWhereTheyAgree) {
  // A unit sphere: a point at radius 0.8 facing out moves to radius 1 with the sphere's normal
  // and offset there; one whose normal is 70° off the sphere's moves but keeps its own normal
  // and offset (across a crease).
  const Mesh sphere = test::build(test::icosphere(4));
  const RowMatrixX3d offsets = vertex_offset_directions(sphere);
  const Eigen::Vector3d d = Eigen::Vector3d(1, 2, 3).normalized();
  const Eigen::Vector3d side = d.cross(Eigen::Vector3d::UnitX()).normalized();
  const Eigen::Vector3d tilted = std::cos(70 * M_PI / 180) * d + std::sin(70 * M_PI / 180) * side;
  RowMatrixX3d points(2, 3), normals(2, 3);
  points.row(0) = points.row(1) = 0.8 * d.transpose();
  normals.row(0) = d.transpose(), normals.row(1) = tilted.transpose();
  RowMatrixX3d off = normals;
  const RowMatrixX3d normals_before = normals;
  project_onto_surface(sphere, offsets, points, normals, &off, 1);
  EXPECT_NEAR(points.row(0).norm(), 1.0, 2e-3);  // on the faceted sphere, within its chord sag
  EXPECT_GT(points.row(0).normalized().dot(d.transpose()), 0.999);
  EXPECT_GT(normals.row(0).dot(d.transpose()), 0.999);
  EXPECT_GT(off.row(0).dot(d.transpose()), 0.99);
  EXPECT_NEAR(points.row(1).norm(), 1.0, 2e-3);
  EXPECT_EQ(normals.row(1), normals_before.row(1));
  EXPECT_EQ(off.row(1), normals_before.row(1));
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
  auto error_of = [&](BakeOptions s) {
    s.transfer.rays = 128;
    BakeResult r = bake(mesh, s);
    return evaluate(ref, vertex_positions(r.mesh), r.mesh.triangles, r.mesh.source_face, r.transfer).rms_percent;
  };
  BakeOptions none, u2, u3, adaptive;
  u2.refine = u3.refine = Refinement::Uniform;
  u2.uniform.levels = 2, u3.uniform.levels = 3;
  const size_t level3 = mesh.num_faces() * 64;
  adaptive.refine = Refinement::Adaptive, adaptive.adaptive.budget = level3;
  const double e0 = error_of(none), e2 = error_of(u2), e3 = error_of(u3), ea = error_of(adaptive);
  EXPECT_LT(e2, e0);
  EXPECT_LT(e3, e2);
  EXPECT_LT(ea, e3) << "adaptive " << ea << "% vs uniform " << e3 << "% at " << level3 << " triangles";
  EXPECT_GT(e3 - ea, 3 * ref.noise_floor * 100);  // adaptive's lead is well above the reference's noise
}

}  // namespace
}  // namespace prtsub
