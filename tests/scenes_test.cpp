// End-to-end checks on the real meshes in ../shared/scenes. A user's clone has none: then these
// tests skip and say so. CI has ../shared beside the checkout, and there they run.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

#include "cli/commands.h"
#include "cli_helpers.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/image_io.h"
#include "prtsub/subdiv/ply.h"
#include "prtsub/subdiv/refine.h"
#include "prtsub/subdiv/simplify.h"
#include "prtsub/prt/transfer.h"
#include "prtsub/subdiv/mesh_io.h"

namespace prtsub {
namespace {

int run(std::vector<std::string> args) {  // quiet: the summaries of ten scenes are noise here
  testing::internal::CaptureStdout();
  int rc = test::run_prtsub(std::move(args));
  testing::internal::GetCapturedStdout();
  return rc;
}

struct SceneFacts {
  const char* file;
  size_t triangles, vertices, boundary_edges;
  size_t duplicate_positions, zero_area;
};

// From ../shared/scenes/README.md ("What is in each mesh").
const SceneFacts kScenes[] = {
    {"cornell_box.obj", 32, 28, 16, 0, 0},          {"spot_control_mesh.obj", 372, 188, 0, 0, 0},
    {"house_on_site.obj", 2710, 2108, 1176, 837, 4}, {"mori_knob.obj", 11970, 6091, 44, 0, 0},
    {"teapot.obj", 15704, 7850, 0, 0, 0},           {"chinese_dragon.obj", 19994, 10000, 6, 0, 0},
    {"bunny.ply", 69451, 34834, 223, 0, 0},         {"sibenik.obj", 75284, 40979, 9182, 761, 11},
    {"armadillo.ply", 345944, 172974, 0, 0, 0},     {"conference.ply", 331179, 194399, 55609, 5366, 0},
};

class Scenes : public ::testing::TestWithParam<SceneFacts> {};

TEST_P(Scenes, LoadsWithTheDocumentedCounts) {
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  const SceneFacts& s = GetParam();
  Mesh m = load_mesh(dir + "/" + s.file);
  EXPECT_EQ(m.input_triangles, s.triangles);
  EXPECT_EQ(m.input_vertices, s.vertices);
  EXPECT_EQ(m.defects.welded_vertices, s.duplicate_positions);
  EXPECT_EQ(m.defects.zero_area_faces, s.zero_area);
  EXPECT_EQ(m.defects.degenerate_faces, 0u);
  EXPECT_EQ(m.defects.unreferenced_vertices, 0u);
  if (s.duplicate_positions == 0) {
    // Nothing to weld: topology exactly as the README counts it.
    EXPECT_EQ(m.num_faces(), s.triangles);
    EXPECT_EQ(m.defects.boundary_edges, s.boundary_edges);
    EXPECT_EQ(m.defects.non_manifold_edges, 0u);
    EXPECT_EQ(m.defects.winding_conflicts, 0u);
  }
  EXPECT_TRUE(m.normals.allFinite());
  EXPECT_GE(m.num_vertices(), static_cast<size_t>(m.positions.rows()));
}


TEST_P(Scenes, BakesAndRendersWithTheAutoCamera) {
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  test::TempDir tmp;
  const std::string asset = tmp.path("a.ply"), frame = tmp.path("f.exr"), rep = tmp.path("r.json");
  ASSERT_EQ(run({"bake", dir + "/" + GetParam().file, "-o", asset, "--rays", "4", "--order", "3"}), 0);
  ASSERT_EQ(run({"render", asset, "--light", "sky", "--light", "sun:1,3,2", "-o", frame, "--size", "160,120", "--camera",
                 "auto", "--report", rep}),
            0);
  // The auto camera frames the asset's bounding sphere: its cone of view is tangent to the sphere
  // at the frame's shorter side, so the asset lies inside the inscribed circle of the frame. It
  // covers a good part of that circle, never the frame's corners, and at most the circle's share
  // of the frame, π·60²/(160·120) = 0.589 (0.6 with the pixels the circle's edge cuts).
  const std::string json = read_file_bytes(rep);
  const size_t at = json.find("\"pixels_covered\": ");
  ASSERT_NE(at, std::string::npos);
  const long covered = std::stol(json.substr(at + 18));
  EXPECT_GT(covered, 160 * 120 / 20) << GetParam().file;
  EXPECT_LE(covered, 0.6 * 160 * 120) << GetParam().file;
  const Image f = read_image(frame);
  for (int x : {0, 159})
    for (int y : {0, 119}) EXPECT_EQ(f.at(x, y, 3), 0.f) << GetParam().file << ": corner " << x << "," << y << " is covered";
}


TEST(ScenesRefine, LongestEdgePathsStayLinearOnSkinnyArchitecture) {
  // Sibenik's long needles make longest-edge paths dozens of faces deep. Resuming a path one
  // step back after each split keeps the walk linear: at most two steps per split plus a few
  // per popped face. (Restarting from the popped face made this run 200x slower.)
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  Mesh m = load_mesh(dir + "/sibenik.obj");
  struct Curvy : RefinementSignal {
    double edge_error(const EdgeView& e) const override { return std::abs(e.va[0] - e.vb[0]) + 1e-3 * (e.pa - e.pb).norm(); }
    void compute_values(const std::vector<NewVertex>& b, const RowMatrixXd&, RowMatrixXd& out) override {
      for (size_t i = 0; i < b.size(); ++i) out(static_cast<Eigen::Index>(i), 0) = std::sin(b[i].position.x()) * std::cos(b[i].position.z());
    }
  } signal;
  RowMatrixXd v(static_cast<Eigen::Index>(m.num_vertices()), 1);
  for (uint32_t i = 0; i < m.num_vertices(); ++i) v(i, 0) = std::sin(m.point(i).x()) * std::cos(m.point(i).z());
  RefineStats st = refine_adaptive(m, v, signal, RefineOptions{2 * m.num_faces(), 256, 0});
  EXPECT_EQ(m.num_faces(), 2 * 75284u);
  EXPECT_GT(st.splits, 10000u);
  EXPECT_LE(st.walk_steps, 2 * st.splits + 3 * st.faces_popped);
}

TEST(ScenesRefine, DegenerateFacesDoNotSoakUpTheBudget) {
  // house_on_site has zero-area faces lying along the edges of large ones. Before zero-area
  // faces were kept out of the queue, and longest-edge paths stopped at them, refinement to 4x
  // the input put 57% of all output faces into one input triangle (collinear children along
  // its edge) and the error did not fall with the budget.
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  test::TempDir tmp;
  ASSERT_EQ(run({"bake", dir + "/house_on_site.obj", "-o", tmp.path("h.ply"), "--refine", "adaptive", "--budget", "10840",
                 "--rays", "32"}),
            0);
  Asset a = read_asset(tmp.path("h.ply"));
  ASSERT_EQ(a.triangles.size(), 10840u);
  std::map<uint32_t, size_t> per_source;
  size_t most = 0;
  for (uint32_t s : a.source_face) most = std::max(most, ++per_source[s]);
  EXPECT_LT(most, a.triangles.size() * 15 / 100);
}

TEST(ScenesSimplify, MoriKnobAtATenthCollapsesItsCreaseCornersAndKeepsItsTopologyAndGuards) {
  // mori_knob's creases all meet in corners: while corners were locked it stopped near 2.5k of
  // its 12k triangles. With corners collapsing it reaches a tenth exactly (it has a boundary),
  // nothing locked. Half-edge collapses keep the topology (the Euler characteristic and the
  // absence of non-manifold edges and winding conflicts) and every position an input position,
  // the moved render vertices' too; no face turns against its own vertices' normals (24 did
  // before the guard against it).
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  Mesh m = load_mesh(dir + "/mori_knob.obj");
  const Mesh in = m;
  ASSERT_EQ(in.num_faces(), 11970u);
  RowMatrixXd v(Eigen::Index(m.num_vertices()), 2);
  for (uint32_t i = 0; i < m.num_vertices(); ++i) {
    const Eigen::Vector3d p = m.point(i), n = m.normals.row(i).transpose();
    v(i, 0) = std::max(n.z(), 0.0), v(i, 1) = std::sin(8 * p.x()) * n.y();
  }
  std::vector<uint32_t> to;
  const SimplifyStats st = simplify(m, v, SimplifyOptions{1197}, &to);
  EXPECT_EQ(m.num_faces(), 1197u) << st.warning;
  EXPECT_EQ(st.locked_vertices, 0u);
  EXPECT_GT(st.corner_collapses, 100u);
  EXPECT_FALSE(st.moved.empty());
  const EdgeCounts e0 = test::position_edges(in), e1 = test::position_edges(m);
  EXPECT_EQ(e1.non_manifold, 0u);
  EXPECT_EQ(e1.winding_conflicts, 0u);
  EXPECT_EQ(long(m.positions.rows()) - long(e1.edges) + long(m.num_faces()), long(in.positions.rows()) - long(e0.edges) + long(in.num_faces()));
  std::set<std::array<double, 3>> inputs;
  for (Eigen::Index p = 0; p < in.positions.rows(); ++p) inputs.insert({in.positions(p, 0), in.positions(p, 1), in.positions(p, 2)});
  for (Eigen::Index p = 0; p < m.positions.rows(); ++p)
    EXPECT_TRUE(inputs.count({m.positions(p, 0), m.positions(p, 1), m.positions(p, 2)})) << "position " << p << " is not an input position";
  size_t against = 0;
  for (const Triangle& t : m.triangles) {
    const Eigen::Vector3d a = m.point(t[0]), b = m.point(t[1]), c = m.point(t[2]);
    const Eigen::Vector3d n = (m.normals.row(t[0]) + m.normals.row(t[1]) + m.normals.row(t[2])).transpose();
    against += (b - a).cross(c - a).dot(n) < 0;
  }
  EXPECT_EQ(against, 0u);
  EXPECT_TRUE(v.allFinite());
}

INSTANTIATE_TEST_SUITE_P(Shared, Scenes, ::testing::ValuesIn(kScenes), [](const auto& param_info) {
  std::string name = param_info.param.file;
  return name.substr(0, name.find('.'));
});

TEST(ScenesTransfer, CornellBoxHasContactShadowsAndNoNaN) {
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  Mesh m = load_mesh(dir + "/cornell_box.obj");
  RayScene scene(m.positions, position_triangles(m));
  RowMatrixX3d p(static_cast<Eigen::Index>(m.num_vertices()), 3);
  for (uint32_t v = 0; v < m.num_vertices(); ++v) p.row(v) = m.point(v).transpose();
  TransferOptions o;
  o.rays = 256;
  RowMatrixXd t = shadowed_transfer(scene, p, m.normals, o);
  ASSERT_TRUE(t.allFinite());
  // Inside a box open at one side, every vertex is partly shadowed: its DC term lies strictly
  // between 0 and the unshadowed π·y00 = sqrt(π)/2.
  const double open_dc = std::sqrt(M_PI) / 2;
  for (Eigen::Index v = 0; v < t.rows(); ++v) {
    EXPECT_LT(t(v, 0), open_dc * 0.999) << "vertex " << v;
    EXPECT_GT(t(v, 0), -1e-9) << "vertex " << v;
  }
}

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

// The paper's claim on a real coarse scene: from the same rays and samples, the least-squares
// fit beats the hat-weighted average, which beats point sampling, for AO and for transfer.
// (BENCHMARKS.md measured 7.0 < 8.4 < 15.5% for AO and 11.9 < 14.6 < 23.1% for transfer; the
// margins are far above the reference's 0.1–0.2% noise floor.)
TEST(ScenesFit, CornellBoxOrdersLsqBelowAverageBelowPoint) {
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  test::TempDir tmp;
  for (const char* signal : {"ao", "transfer"}) {
    const std::string rep = tmp.path(std::string(signal) + ".json");
    testing::internal::CaptureStdout();
    ASSERT_EQ(test::run_prtsub({"eval", "--fits", dir + "/cornell_box.obj", "--signal", signal, "--points", "5000", "--report", rep}), 0);
    testing::internal::GetCapturedStdout();
    std::ifstream in(rep);
    const std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto number = [&](const std::string& key) {
      const size_t at = json.find("\"" + key + "\": ");
      return at == std::string::npos ? NAN : std::atof(json.c_str() + at + key.size() + 4);
    };
    const double point = number("e_point_percent"), avg = number("e_avg_percent"), lsq = number("e_lsq_percent");
    EXPECT_LT(lsq, 0.9 * avg) << signal;
    EXPECT_LT(avg, 0.7 * point) << signal;
    EXPECT_LT(number("e_alpha_percent"), avg) << signal;
  }
}

}  // namespace
}  // namespace prtsub

#include "prtsub/prt/bake.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/path_transfer.h"

namespace prtsub {
namespace {

// eval's interreflected reference (shadowed transfer, plus the bounced light traced as paths with
// a control variate at each bounce) against brute-force path tracing: the textbook estimator of
// all of t_B, direct light included, with no control variate. Both estimate one function, each
// with its variance (the direct part's from its halves, the paths' from their spread); if they
// agree, the mean squared difference over points is the sum of the variances (ratio 1), and a
// bias the size of the noise would make it 2. With 300 points × 16 coefficients the ratio's own
// spread is a few percent. Bounces 0 checks the path tracer's rays against transfer.cpp's.
class ScenesBounceReference : public ::testing::TestWithParam<const char*> {};

TEST_P(ScenesBounceReference, AgreesWithBruteForcePathTracingWithinItsNoise) {
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  const Mesh m = load_mesh(dir + "/" + GetParam());
  const RayScene scene(m.positions, position_triangles(m));
  ReferenceOptions ro;
  ro.points = 300, ro.rays = 2, ro.noise_points = 0;
  const Reference at = make_reference(m, scene, ro);  // only its points
  const RowMatrixX3d corners = vertex_positions(m);
  const PathSurface surface{corners, m.normals, m.triangles};
  const int order = 4;
  for (const int bounces : {0, 3}) {
    TransferOptions t;
    t.order = order, t.rays = 2048, t.seed = 5;
    std::vector<double> var_direct, var_bounced(static_cast<size_t>(at.points.rows()), 0.0), var_brute;
    RowMatrixXd reference = shadowed_transfer(scene, at.points, at.normals, t, nullptr, {}, nullptr, &var_direct);
    PathOptions p;
    p.order = order, p.paths = 2048, p.bounces = bounces, p.seed = 6;
    if (bounces > 0) reference += path_traced_transfer(scene, surface, at.points, at.normals, p, &var_bounced);
    p.paths = 1 << 15, p.plain = true, p.seed = 7;
    const RowMatrixXd brute = path_traced_transfer(scene, surface, at.points, at.normals, p, &var_brute);
    double diff2 = 0, var = 0;
    for (Eigen::Index i = 0; i < at.points.rows(); ++i) {
      const auto k = static_cast<size_t>(i);
      diff2 += (reference.row(i) - brute.row(i)).squaredNorm();
      var += var_direct[k] + var_bounced[k] + var_brute[k];
    }
    const double ratio = diff2 / var, unit = unshadowed_norm(order), n = static_cast<double>(at.points.rows());
    std::printf("%s, %d bounces: RMS difference %.3f%%, expected from the noise %.3f%%, ratio %.3f\n", GetParam(), bounces,
                100 * std::sqrt(diff2 / n) / unit, 100 * std::sqrt(var / n) / unit, ratio);
    EXPECT_LT(ratio, 1.3) << bounces;
    EXPECT_GT(ratio, 0.7) << bounces;
  }
}

INSTANTIATE_TEST_SUITE_P(CornellAndHouse, ScenesBounceReference, ::testing::Values("cornell_box.obj", "house_on_site.obj"));

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

// Bounced light in the fit: the samples gather one bounce and the fit runs again. Against eval's
// bounced reference it lowers the error (measured: Cornell box 14.56 -> 12.75%, house_on_site
// 23.60 -> 18.31% at 3 bounces; BENCHMARKS.md, "Interreflection").
class ScenesBounceFit : public ::testing::TestWithParam<const char*> {};

TEST_P(ScenesBounceFit, FittingBouncedSamplesLowersTheErrorAgainstBouncedLight) {
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  const Mesh m = load_mesh(dir + "/" + GetParam());
  const RayScene scene(m.positions, position_triangles(m));
  BakeOptions o;
  o.bounce.bounces = 3;
  const BakeResult with = bake(m, o);
  o.bounce.fit_samples = false;
  const BakeResult without = bake(m, o);
  ReferenceOptions ro;
  ro.points = 5000, ro.rays = 2048, ro.bounces = 3;
  const Reference ref = make_reference(m, scene, ro);
  const auto error = [&](const BakeResult& r) {
    return evaluate(ref, vertex_positions(r.mesh), r.mesh.triangles, r.mesh.source_face, r.transfer).rms_percent;
  };
  EXPECT_LT(error(with), 0.92 * error(without)) << error(with) << " against " << error(without);
}

INSTANTIATE_TEST_SUITE_P(CornellAndHouse, ScenesBounceFit, ::testing::Values("cornell_box.obj", "house_on_site.obj"));

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

// bounce_noise against the truth: the passes' surface noise measured by running them twice with
// seeds of their own (area-weighted mean of ‖Δ‖²/2 over every vertex, halved as bounce_noise
// halves it). --error uses the estimate, made before the passes run, to choose fewer bounce rays
// where the target leaves room, so it must not fall below the truth, and should not be far
// above it, or it saves nothing.
class ScenesBounceNoise : public ::testing::TestWithParam<const char*> {};

TEST_P(ScenesBounceNoise, AheadOfThePassesItIsAtLeastTheirs) {
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  const Mesh m = load_mesh(dir + "/" + GetParam());
  const RayScene scene(m.positions, position_triangles(m));
  TransferOptions t;
  t.order = 3, t.rays = 64, t.seed = 11;
  const RowMatrixXd direct = shadowed_transfer(scene, vertex_positions(m), m.normals, t);
  BounceOptions b;
  b.bounces = 3, b.rays = 32, b.seed = 21;
  const RowMatrixXd one = interreflected_transfer(m, scene, direct, b);
  b.seed = 22;
  const RowMatrixXd two = interreflected_transfer(m, scene, direct, b);
  const std::vector<double> area = vertex_areas(m);
  double sum = 0, weight = 0;
  for (size_t i = 0; i < area.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    sum += area[i] * (one.row(r) - two.row(r)).squaredNorm() / 2, weight += area[i];
  }
  const double truth = sum / weight / 2;
  uint64_t rays = 0;
  const double ahead = bounce_noise(m, scene, direct, b, 2048, &rays);
  std::printf("%s: the passes' noise %.3g; bounce_noise ahead of them %.3g (%.2f)\n", GetParam(), truth, ahead, ahead / truth);
  EXPECT_GT(ahead, 0.9 * truth);
  EXPECT_LT(ahead, 3.0 * truth);
  const size_t stride = (m.num_vertices() + 2047) / 2048, picked = (m.num_vertices() + stride - 1) / stride;
  EXPECT_EQ(rays, uint64_t(2) * 32 * picked);  // two gathers at the same vertices
}

INSTANTIATE_TEST_SUITE_P(Interiors, ScenesBounceNoise,
                         ::testing::Values("cornell_box.obj", "house_on_site.obj", "conference.ply", "mori_knob.obj", "sibenik.obj"));

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

// Both ways at house_on_site's own count (issue 12, point 3): the same 2,710 triangles placed
// where the transfer varies, against the input's own, one reference judging both (eval's: 20,000
// points at 1024 rays). At the default seed 0.66x (0.660-0.695x over seeds 0-3, docs/simplification.md);
// the bound, 0.68x, lies between that and what the bake did with half the fit's samples (0.69x),
// without its further cycle (0.72x) or with refinement's old batches (0.85x). Seeds are fixed,
// so the figure is exact here.
TEST(ScenesBothWays, HouseOnSiteAtItsOwnCountBeatsItsOwnTrianglesByThirty) {
  const std::string dir = test::shared_scenes();
  if (dir.empty()) GTEST_SKIP() << "needs ../shared/scenes beside the checkout (present in CI)";
  const Mesh m = load_mesh(dir + "/house_on_site.obj");
  const RayScene scene(m.positions, position_triangles(m));
  BakeOptions o;
  const BakeResult none = bake(m, o);
  o.refine = Refinement::Auto, o.adaptive.budget = m.num_faces();
  const BakeResult r = bake(m, o);
  ASSERT_EQ(r.mesh.num_faces(), m.num_faces());
  EXPECT_EQ(r.auto_cycles, 1);
  EXPECT_TRUE(r.transfer.allFinite());
  ReferenceOptions ro;
  ro.points = 20000, ro.rays = 1024;
  const Reference ref = make_reference(m, scene, ro);
  const double e_none = evaluate(ref, vertex_positions(none.mesh), none.mesh.triangles, none.mesh.source_face, none.transfer).rms_percent;
  const double e = evaluate_by_closest_point(ref, vertex_positions(r.mesh), r.mesh.triangles, r.transfer).rms_percent;
  std::printf("house_on_site: input's own triangles %.3f%%, both ways %.3f%% (%.3fx)\n", e_none, e, e / e_none);
  EXPECT_LT(e, 0.68 * e_none);
}

}  // namespace
}  // namespace prtsub
