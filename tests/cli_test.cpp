#include "cli/commands.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <utility>

#include <sys/wait.h>

#include "cli_helpers.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/image_io.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/mesh_io.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

int run(std::vector<std::string> args) { return test::run_prtsub(std::move(args)); }

class Cli : public ::testing::Test {
 protected:
  test::TempDir dir;
  std::string scene() {
    std::string p = dir.path("scene.obj");
    test::write_obj(p, test::merge(test::icosphere(1), test::quad(3.0, -1.0, true)));
    return p;
  }
  size_t files() const {
    size_t n = 0;
    for (auto& e : std::filesystem::directory_iterator(dir.path(""))) n += e.is_regular_file();
    return n;
  }
};

TEST_F(Cli, BakeWritesAnAssetAndAReportWithTheDocumentedKeys) {
  std::string in = scene(), out = dir.path("a.ply"), rep = dir.path("r.json");
  ASSERT_EQ(run({"bake", in, "-o", out, "--order", "3", "--rays", "16", "--report", rep}), 0);
  Asset a = read_asset(out);
  EXPECT_EQ(a.order, 3);
  EXPECT_EQ(a.triangles.size(), 82u);
  std::string json = read_file_bytes(rep);
  for (const char* key : {"triangles_in", "vertices_in", "triangles_out", "vertices_out", "rays", "seconds_total",
                          "seconds_load", "seconds_scene", "seconds_transfer", "seconds_write", "rays_per_second",
                          "defects_zero_area_faces", "defects_non_manifold_edges", "defects_winding_conflicts",
                          "fit", "samples", "sample_rays", "sample_rays_auto", "sample_rays_trials", "sample_rays_variation",
                          "sample_rays_noise_points", "sample_rays_noise_rays", "alpha", "solve_memory_mib", "seconds_fit_factor"})
    EXPECT_NE(json.find(std::string("\"") + key + "\""), std::string::npos) << key;
  // 16 rays at each vertex, then the pilot's, the samples' (the rays per sample the pilot chose)
  // and the vertices' second round.
  auto number = [&](const std::string& key) {
    const size_t at = json.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key;
    return at == std::string::npos ? -1.0 : std::atof(json.c_str() + at + key.size() + 4);
  };
  EXPECT_EQ(number("rays"), double(a.transfer.rows() * 16) + number("pilot_rays") + number("sample_rays") * number("samples") + number("top_up_rays"));
  EXPECT_EQ(json.find("\"sample_rays_auto\": true") != std::string::npos, true);
  // --sample-rays fixes the count: nothing measured, the samples traced with it.
  std::string rep8 = dir.path("r8.json");
  ASSERT_EQ(run({"bake", in, "-o", out, "--order", "3", "--rays", "16", "--sample-rays", "8", "--report", rep8}), 0);
  const std::string json8 = read_file_bytes(rep8);
  EXPECT_NE(json8.find("\"sample_rays\": 8,"), std::string::npos);
  EXPECT_NE(json8.find("\"sample_rays_auto\": false"), std::string::npos);
  EXPECT_EQ(json8.find("\"sample_rays_trials\""), std::string::npos);
  double faces = 0;
  for (const char* bin : {"0", "1", "2_3", "4_7", "8_15", "16_31", "32_63", "64_up"}) faces += number(std::string("faces_with_samples_") + bin);
  EXPECT_EQ(faces, 82);
  EXPECT_EQ(number("faces_with_samples_0"), number("interpolated_faces"));
  // Every vertex by its rays (16, 32, 64, 128, 256: the second round doubles a vertex's rays at
  // most four times), and the extra rays those counts imply are the second round's.
  double vertices = 0, extra = 0, factor = 1;
  for (const char* bin : {"1x", "2x", "4x", "8x", "16x_up"}) {
    const double n = number(std::string("vertices_with_rays_") + bin);
    vertices += n, extra += n * 16 * (factor - 1), factor *= 2;
  }
  EXPECT_EQ(vertices, double(a.transfer.rows()));
  EXPECT_EQ(number("vertices_with_rays_1x") + number("top_up_vertices"), vertices);
  EXPECT_EQ(extra, number("top_up_rays"));
  EXPECT_GT(number("predicted_error_percent"), 0);
  EXPECT_GT(number("predicted_error_samples"), 0);
  EXPECT_NE(json.find("\"fit\": \"lsq\""), std::string::npos);
  EXPECT_EQ(run({"inspect", out}), 0);
  EXPECT_EQ(run({"inspect", out, "--report", dir.path("i.json")}), 0);
  EXPECT_NE(read_file_bytes(dir.path("i.json")).find("\"order_99_percent_energy\""), std::string::npos);
}

TEST_F(Cli, AmbientOcclusionAssetsHoldOneClampedValuePerVertex) {
  std::string in = dir.path("ao_scene.obj"), out = dir.path("ao.ply"), rep = dir.path("r.json");
  test::write_obj(in, test::merge(test::icosphere(1), test::quad(3.0, -1.3, true)));
  for (const char* fit : {"point", "average", "lsq"}) {
    ASSERT_EQ(run({"bake", in, "-o", out, "--signal", "ao", "--fit", fit, "--rays", "64", "--report", rep}), 0) << fit;
    Asset a = read_asset(out);
    EXPECT_EQ(a.signal, AssetSignal::Ao);
    EXPECT_EQ(a.transfer.cols(), 1);
    const Eigen::ArrayXd ao = a.transfer.col(0).array() * kAoPerT0;
    EXPECT_GE(ao.minCoeff(), 0.0);
    EXPECT_LE(ao.maxCoeff(), 1.0);
    // The sphere's top vertex sees open sky: exactly 1 when point-sampled (the estimator is exact
    // when nothing is hit); fitted values there also average samples on the coarse sphere's
    // faces, whose interpolated normals graze neighbouring faces. Its lowest vertex faces the
    // plane 0.3 below: a 3×3 square seen from above, where most of the cosine lobe lands.
    Eigen::Index top = 0, bottom = 0;
    for (Eigen::Index v = 0; v < a.positions.rows(); ++v) {
      if (std::abs(a.positions.row(v).norm() - 1) > 1e-5) continue;
      if (a.positions(v, 2) > a.positions(top, 2)) top = v;
      if (a.positions(v, 2) < a.positions(bottom, 2)) bottom = v;
    }
    EXPECT_NEAR(ao[top], 1.0, std::string(fit) == "point" ? 1e-6 : 0.03) << fit;
    EXPECT_LT(ao[bottom], 0.2) << fit;
    const std::string json = read_file_bytes(rep);
    EXPECT_NE(json.find("\"clamped_values\""), std::string::npos);
    EXPECT_NE(json.find("\"signal\": \"ao\""), std::string::npos);
    EXPECT_EQ(run({"eval", out, "--source", in, "--points", "500"}), 0);
  }
  // inspect and render take AO assets too.
  EXPECT_EQ(run({"inspect", out, "--report", dir.path("i.json")}), 0);
  EXPECT_NE(read_file_bytes(dir.path("i.json")).find("\"signal\": \"ao\""), std::string::npos);
  EXPECT_EQ(run({"render", out, "--light", "sky", "-o", dir.path("ao.png"), "--size", "64,48"}), 0);
  EXPECT_TRUE(test::file_exists(dir.path("ao.png")));
  // The ao property is what a consumer reads.
  EXPECT_NE(read_file_bytes(out).find("property float ao"), std::string::npos);
  EXPECT_EQ(read_file_bytes(out).find("property float t0"), std::string::npos);
  EXPECT_EQ(run({"bake", in, "-o", out, "--signal", "light"}), 2);
  EXPECT_EQ(run({"bake", in, "-o", out, "--fit", "spline"}), 2);
  // --alpha takes a number or auto; anything else names the option and the value.
  EXPECT_EQ(run({"bake", in, "-o", out, "--alpha", "0.02"}), 0);
  EXPECT_EQ(run({"bake", in, "-o", out, "--alpha", "auto", "--report", dir.path("alpha.json")}), 0);
  EXPECT_NE(read_file_bytes(dir.path("alpha.json")).find("\"alpha_auto\": true"), std::string::npos);
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"bake", in, "-o", out, "--alpha", "-1"}), 2);
  EXPECT_EQ(run({"bake", in, "-o", out, "--alpha", "some"}), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("--alpha: expected a non-negative number or auto, got '-1'"), std::string::npos) << err;
  EXPECT_NE(err.find("got 'some'"), std::string::npos) << err;
}

TEST_F(Cli, EvalFitsReportsThePapersFourErrorsAndBenchTimesTheFit) {
  // A coarse sphere over a plane: the fit's home ground. The four columns come from one set of
  // rays; on this scene the paper's ordering holds with room to spare.
  std::string in = dir.path("fits.obj"), rep = dir.path("f.json");
  test::write_obj(in, test::merge(test::icosphere(1), test::quad(3.0, -1.3, true)));
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"eval", "--fits", in, "--signal", "ao", "--points", "3000", "--report", rep}), 0);
  testing::internal::GetCapturedStdout();
  const std::string json = read_file_bytes(rep);
  auto number = [&](const std::string& key) {
    const size_t at = json.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key;
    return at == std::string::npos ? NAN : std::atof(json.c_str() + at + key.size() + 4);
  };
  const double point = number("e_point_percent"), avg = number("e_avg_percent"), lsq = number("e_lsq_percent"),
               alpha = number("e_alpha_percent");
  EXPECT_LT(avg, point);
  EXPECT_LT(lsq, avg);
  EXPECT_LT(alpha, point);
  // The default (noise-weighted, non-negative) never loses to point sampling on its own rays.
  const double fit_default = number("e_default_percent");
  EXPECT_LE(fit_default, point);
  EXPECT_GT(number("kept_correction"), 0.0);
  EXPECT_LE(number("kept_correction"), 1.0);
  EXPECT_GE(number("samples"), number("sampled_faces"));
  EXPECT_GT(number("sampled_faces"), 0);
  EXPECT_GE(number("solve_memory_mib_alpha"), 0.0);
  EXPECT_GT(number("noise_floor_percent"), 0.0);
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({"bench", in, "--solve", "--repeat", "1", "--report", dir.path("s.json")}), 0);
  EXPECT_EQ(run({"bench", in, "--at", "samples", "--rays", "8", "--repeat", "1", "--report", dir.path("b.json")}), 0);
  testing::internal::GetCapturedStdout();
  EXPECT_NE(read_file_bytes(dir.path("s.json")).find("\"seconds_fit_factor\""), std::string::npos);
  EXPECT_NE(read_file_bytes(dir.path("b.json")).find("\"at\": \"samples\""), std::string::npos);
}

TEST_F(Cli, OrderAutoBakesAtTheOrderItChoseAndSaysWhy) {
  const std::string in = scene(), asset = dir.path("a.ply"), sky = dir.path("s.ply");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--order", "auto", "--rays", "16", "--fit", "point", "--report", dir.path("a.json")}), 0);
  ASSERT_EQ(run({"bake", in, "-o", sky, "--order", "auto", "--order-light", "const:1,1,1", "--rays", "16", "--fit", "point"}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("  order auto: "), std::string::npos) << out;
  EXPECT_NE(out.find("per order, truncation/noise %: 1: "), std::string::npos) << out;
  const std::string j = read_file_bytes(dir.path("a.json"));
  const double order = test::json_number(j, "order");
  EXPECT_EQ(read_asset(asset).order, order);
  EXPECT_EQ(test::json_number(j, "coefficients"), order * order);
  EXPECT_LE(test::json_number(j, "order_truncation_percent"), test::json_number(j, "order_tolerance_percent"));
  EXPECT_EQ(read_asset(sky).order, 1);  // a constant light needs band 0 only
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"bake", in, "-o", dir.path("x.ply"), "--order-light", "sky"}), 2);
  EXPECT_EQ(run({"bake", in, "-o", dir.path("x.ply"), "--order", "eleven"}), 2);
  EXPECT_EQ(run({"compare", in, "--order", "auto", "-o", dir.path("cmp")}), 2);
  EXPECT_EQ(run({"bench", in, "--order", "auto"}), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("--order auto is for bake"), std::string::npos) << err;
}

TEST_F(Cli, EarlyStopSaysHowManyRaysEachVertexTracedAndRaysFixedTurnsItOff) {
  const std::string in = scene(), asset = dir.path("a.ply"), fixed = dir.path("f.ply");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--first-rays", "8", "--rays", "64", "--fit", "point", "--report", dir.path("a.json")}), 0);
  ASSERT_EQ(run({"bake", in, "-o", fixed, "--first-rays", "8", "--rays-fixed", "64", "--fit", "point", "--report", dir.path("f.json")}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("  early stop: from 8 rays, "), std::string::npos) << out;
  EXPECT_NE(out.find("vertices by rays: 8: "), std::string::npos) << out;
  const std::string j = read_file_bytes(dir.path("a.json")), f = read_file_bytes(dir.path("f.json"));
  const double V = test::json_number(j, "vertices_out");
  // Every vertex's count is in the distribution, and the rays are the first round's plus the rounds'.
  EXPECT_EQ(test::json_number(j, "rays"), 8 * V + test::json_number(j, "early_stop_rays"));
  EXPECT_NEAR(test::json_number(j, "vertex_rays_mean") * V, test::json_number(j, "rays"), 1e-6 * test::json_number(j, "rays"));
  EXPECT_GT(test::json_number(j, "early_stop_rays"), 0);  // the sphere's lower half sees the plane
  EXPECT_LT(test::json_number(j, "rays"), 64 * V);        // its upper half does not
  EXPECT_LE(test::json_number(j, "early_stop_rounds"), 3);
  EXPECT_EQ(test::json_number(f, "rays"), 64 * V);  // --rays-fixed: no early stop
  EXPECT_EQ(f.find("\"early_stop_rounds\""), std::string::npos);
  const auto& meta = read_asset(asset).metadata;
  bool recorded = false;
  for (const auto& [k, v] : meta) recorded |= k == "early_stop";
  EXPECT_TRUE(recorded);
}

TEST_F(Cli, BenchTimesABouncePassAgainstTheBareClosestHitLoopOverTheSameRays) {
  // Every ray from inside a closed room hits; from a plate under the open sky, none does.
  const std::string room = dir.path("room.obj"), plate = dir.path("plate.obj");
  test::write_obj(room, test::closed_room());
  test::write_obj(plate, test::quad(1.0, 0.0, true));
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bench", room, "--at", "bounces", "--rays", "32", "--repeat", "2", "--crease-angle", "0", "--report", dir.path("r.json")}), 0);
  ASSERT_EQ(run({"bench", plate, "--at", "bounces", "--rays", "32", "--repeat", "1", "--report", dir.path("p.json")}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("of the closest-hit loop"), std::string::npos) << out;
  const std::string r = read_file_bytes(dir.path("r.json")), p = read_file_bytes(dir.path("p.json"));
  EXPECT_EQ(test::json_number(r, "hit_fraction"), 1.0);
  EXPECT_EQ(test::json_number(p, "hit_fraction"), 0.0);
  EXPECT_EQ(test::json_number(r, "rays"), 32 * test::json_number(r, "vertices"));
  EXPECT_GT(test::json_number(r, "bounce_over_bare"), 0.0);
}

TEST_F(Cli, BadInputExitsNonZeroAndLeavesNoOutput) {
  test::write_text(dir.path("nan.obj"), "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
  test::write_text(dir.path("empty.obj"), "");
  size_t before = files();
  EXPECT_EQ(run({"bake", dir.path("nan.obj"), "-o", dir.path("out.ply")}), 1);
  EXPECT_EQ(run({"bake", dir.path("empty.obj"), "-o", dir.path("out.ply"), "--report", dir.path("r.json")}), 1);
  EXPECT_EQ(run({"bake", dir.path("missing.obj"), "-o", dir.path("out.ply")}), 1);
  EXPECT_EQ(run({"bake", dir.path("nan.obj"), "-o", dir.path("no/such/dir/out.ply")}), 1);
  EXPECT_EQ(files(), before);  // no asset, no report, no temporary file
  EXPECT_EQ(run({"inspect", dir.path("nan.obj")}), 1);
}

TEST_F(Cli, UsageErrorsNameTheOption) {
  std::string in = scene();
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"bake", in, "-o", dir.path("a.ply"), "--bogus", "1"}), 2);
  EXPECT_EQ(run({"bake", in, "-o", dir.path("a.ply"), "--order", "11"}), 2);
  EXPECT_EQ(run({"bake", in, "-o", dir.path("a.ply"), "--rays", "many"}), 2);
  EXPECT_EQ(run({"bake", in, "-o", dir.path("a.ply"), "--crease-angle", "-5"}), 2);
  EXPECT_EQ(run({"bake", in}), 2);
  EXPECT_EQ(run({"bake", in, "-o"}), 2);
  EXPECT_EQ(run({"frobnicate"}), 2);
  std::string err = testing::internal::GetCapturedStderr();
  for (const char* what : {"--bogus", "--order", "--rays", "--crease-angle", "-o ASSET.ply", "--output", "frobnicate"})
    EXPECT_NE(err.find(what), std::string::npos) << what << " in:\n" << err;
  EXPECT_EQ(files(), 1u);  // only the scene
}

TEST_F(Cli, HelpForEveryCommand) {
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({"--help"}), 0);
  for (const char* c : {"bake", "inspect", "bench"}) EXPECT_EQ(run({c, "--help"}), 0);
  std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("--crease-angle"), std::string::npos);
  EXPECT_NE(out.find("usage: prtsub inspect"), std::string::npos);
}

TEST_F(Cli, BenchReportsBothRates) {
  std::string in = scene(), rep = dir.path("b.json");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bench", in, "--rays", "8", "--repeat", "1", "--report", rep}), 0);
  testing::internal::GetCapturedStdout();
  std::string json = read_file_bytes(rep);
  EXPECT_NE(json.find("\"transfer_rays_per_second\""), std::string::npos);
  EXPECT_NE(json.find("\"bare_rays_per_second\""), std::string::npos);
}

TEST_F(Cli, TheImageLibraryLoadsOnlyForCommandsThatUseImages) {
  // The dynamic loader's own log (LD_DEBUG=libs) names every library it opens: OpenImageIO
  // only for a command that reads or writes an image, through the image module. Without the
  // module, such a command fails in one line naming it, and writes nothing.
  const std::string asset = dir.path("a.ply"), log = dir.path("log.txt");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", scene(), "-o", asset, "--rays", "8", "--fit", "point"}), 0);
  testing::internal::GetCapturedStdout();
  auto opened = [&](const std::string& args, const std::string& env = "") {
    const std::string cmd = env + " LD_DEBUG=libs " + PRTSUB_BINARY + " " + args + " > /dev/null 2> " + log;
    const int status = std::system(cmd.c_str());
    const std::string text = read_file_bytes(log);
    size_t n = 0;
    for (size_t at = text.find("libOpenImageIO"); at != std::string::npos; at = text.find("libOpenImageIO", at + 1)) ++n;
    return std::make_pair(status, n);
  };
  EXPECT_EQ(opened("--version"), std::make_pair(0, size_t(0)));
  EXPECT_EQ(opened("inspect " + asset), std::make_pair(0, size_t(0)));
  const auto rendered = opened("render " + asset + " --light sky:1,1,1 --size 32,24 -o " + dir.path("f.png"));
  EXPECT_EQ(rendered.first, 0);
  EXPECT_GT(rendered.second, 0u);
  EXPECT_TRUE(test::file_exists(dir.path("f.png")));
  const std::string missing = dir.path("no_module.so");
  const std::string cmd = "PRTSUB_IMAGE_MODULE=" + missing + " " + PRTSUB_BINARY + " render " + asset +
                          " --light sky:1,1,1 --size 32,24 -o " + dir.path("g.png") + " > /dev/null 2> " + log;
  EXPECT_EQ(WEXITSTATUS(std::system(cmd.c_str())), 1);
  EXPECT_EQ(read_file_bytes(log), "prtsub: error: cannot load the image module (reading and writing images needs it): tried " + missing +
                                      " (missing)\n");
  EXPECT_FALSE(test::file_exists(dir.path("g.png")));
}

TEST_F(Cli, BundledExampleBakes) {
  std::string example = std::string(PRTSUB_EXAMPLES) + "/spot/spot_control_mesh.obj";
  ASSERT_TRUE(test::file_exists(example));
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({"bake", example, "-o", dir.path("spot.ply"), "--rays", "32"}), 0);
  testing::internal::GetCapturedStdout();
  EXPECT_EQ(read_asset(dir.path("spot.ply")).triangles.size(), 372u);
}

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

TEST_F(Cli, RenderAndDiffProduceFramesAndNumbers) {
  std::string in = scene(), asset = dir.path("a.ply");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--rays", "16"}), 0);
  EXPECT_EQ(run({"render", asset, "--light", "sky", "--light-rotate", "x,30", "-o", dir.path("g.exr"), "--size", "64,48"}), 0);
  EXPECT_EQ(run({"render", asset, "--light", "sky", "--light-rotate", "x,30", "-o", dir.path("r.exr"), "--size", "64,48",
                 "--reference", "--rays", "64", "--compare-bare", "--report", dir.path("r.json")}),
            0);
  EXPECT_EQ(run({"render", asset, "--light", "random:4", "-o", dir.path("g.png"), "--size", "64,48", "--exposure", "2",
                 "--camera", "eye=4,3,5:target=0,0,0:up=0,1,0:fov=35"}),
            0);
  EXPECT_EQ(run({"diff", dir.path("g.exr"), dir.path("r.exr"), "-o", dir.path("heat.png"), "--report", dir.path("d.json")}), 0);
  testing::internal::GetCapturedStdout();
  for (const char* f : {"g.exr", "r.exr", "g.png", "heat.png"}) EXPECT_TRUE(test::file_exists(dir.path(f))) << f;
  std::string rj = read_file_bytes(dir.path("r.json")), dj = read_file_bytes(dir.path("d.json"));
  EXPECT_NE(rj.find("\"reference_rays_per_second\""), std::string::npos);
  EXPECT_NE(rj.find("\"bare_rays_per_second\""), std::string::npos);
  EXPECT_NE(dj.find("\"rmse_percent\""), std::string::npos);
  EXPECT_NE(dj.find("\"psnr_db\""), std::string::npos);
}

TEST_F(Cli, RenderRejectsBadLightsCamerasAndSizesWithoutOutput) {
  std::string in = scene(), asset = dir.path("a.ply");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--rays", "4"}), 0);
  testing::internal::GetCapturedStdout();
  const size_t before = files();
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"render", asset, "--light", "moon:1", "-o", dir.path("f.exr")}), 2);
  EXPECT_EQ(run({"render", asset, "--light", "env:" + dir.path("nope.exr"), "-o", dir.path("f.exr")}), 1);
  EXPECT_EQ(run({"render", asset, "--light", "sky", "--camera", "eye=1,1,1", "-o", dir.path("f.exr")}), 2);
  EXPECT_EQ(run({"render", asset, "--light", "sky", "--size", "0,10", "-o", dir.path("f.exr")}), 2);
  EXPECT_EQ(run({"render", asset, "--light", "sky", "-o", dir.path("f.tga")}), 1);
  EXPECT_EQ(run({"render", asset, "-o", dir.path("f.exr")}), 2);
  EXPECT_EQ(run({"render", in, "--light", "sky", "-o", dir.path("f.exr")}), 1);  // a mesh, not an asset
  EXPECT_EQ(run({"diff", asset, dir.path("missing.exr")}), 1);
  std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("moon"), std::string::npos);
  EXPECT_NE(err.find("--size"), std::string::npos);
  EXPECT_EQ(files(), before);
}

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

TEST_F(Cli, EvalAndCompareWriteTheirTablesAndReports) {
  std::string in = scene(), asset = dir.path("a.ply");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--rays", "16", "--refine", "adaptive", "--budget", "400", "--report", dir.path("b.json")}), 0);
  ASSERT_EQ(run({"eval", asset, "--source", in, "--points", "500", "--report", dir.path("e.json")}), 0);
  ASSERT_EQ(run({"compare", in, "--budgets", "300,700", "--max-levels", "2", "--rays", "8", "--eval-points", "300",
                 "--frame-size", "64,48", "--frame-rays", "8", "-o", dir.path("cmp/nested")}),
            0);
  testing::internal::GetCapturedStdout();
  EXPECT_EQ(read_asset(asset).triangles.size(), 400u);
  const std::string b = read_file_bytes(dir.path("b.json")), e = read_file_bytes(dir.path("e.json"));
  for (const char* key : {"\"min_angle_before_deg\"", "\"min_angle_after_deg\"", "\"splits\"", "\"seconds_refine\""})
    EXPECT_NE(b.find(key), std::string::npos) << key;
  for (const char* key : {"\"rms_percent\"", "\"p95_percent\"", "\"noise_floor_percent\"", "\"reference_points\": 500",
                          "\"reference_rays\": 128"})
    EXPECT_NE(e.find(key), std::string::npos) << key;
  const std::string csv = read_file_bytes(dir.path("cmp/nested/results.csv"));
  // none, uniform levels 1 (328) and 2 (1312 > 700 * 5/4: not run), adaptive at 300, 328, 700 × 6
  // estimates; none, uniform and the default estimate each with point and lsq values.
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 2 + 2 + 18 + 3);
  EXPECT_NE(csv.find("uniform,,point,328,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("uniform,,lsq,328,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("adaptive,root,lsq,700,"), std::string::npos) << csv;
  EXPECT_EQ(csv.find("adaptive,length,lsq"), std::string::npos) << csv;
  EXPECT_EQ(csv.find("adaptive,probe,lsq"), std::string::npos) << csv;
  const std::string html = read_file_bytes(dir.path("cmp/nested/report.html"));
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  EXPECT_NE(html.find("<linearGradient id='heat'>"), std::string::npos);  // the heat maps' one scale, as a bar
  EXPECT_NE(html.find("25% or more"), std::string::npos);
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"compare", in, "--budgets", "300,x", "-o", dir.path("c2")}), 2);
  EXPECT_EQ(run({"bake", in, "-o", dir.path("z.ply"), "--refine", "adaptive"}), 2);
  EXPECT_EQ(run({"bake", in, "-o", dir.path("z.ply"), "--refine", "sideways"}), 2);
  EXPECT_EQ(run({"eval", asset}), 2);
  testing::internal::GetCapturedStderr();
}

TEST_F(Cli, ABouncedAssetIsJudgedAndRenderedAgainstBouncedLightAtItsOwnAlbedo) {
  const std::string in = scene(), direct = dir.path("d.ply"), bounced = dir.path("b.ply");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", direct, "--rays", "32"}), 0);
  ASSERT_EQ(run({"bake", in, "-o", bounced, "--rays", "32", "--bounces", "2", "--albedo", "0.6"}), 0);
  ASSERT_EQ(run({"eval", bounced, "--source", in, "--points", "300", "--paths", "64", "--report", dir.path("e.json")}), 0);
  ASSERT_EQ(run({"eval", direct, "--source", in, "--points", "300", "--report", dir.path("d.json")}), 0);
  for (const std::string& a : {direct, bounced})
    ASSERT_EQ(run({"render", a, "--light", "const:1,1,1", "--reference", "--size", "48,36", "--rays", "64", "-o", a + ".png", "--albedo",
                   "0.6", "--report", a + ".json"}),
              0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("bounced:    2 bounces at albedo 0.6: 64 paths per point through the source"), std::string::npos) << out;
  const std::string e = read_file_bytes(dir.path("e.json")), d = read_file_bytes(dir.path("d.json"));
  EXPECT_EQ(test::json_number(e, "reference_bounces"), 2);
  EXPECT_EQ(test::json_number(e, "albedo"), 0.6);
  EXPECT_EQ(test::json_number(e, "reference_paths"), 64);
  EXPECT_EQ(test::json_number(d, "reference_bounces"), 0);
  EXPECT_TRUE(std::isnan(test::json_number(d, "reference_paths")));
  // The ground under the sphere receives the sphere's light: the bounced reference frame is the
  // brighter one, and says what it traced.
  const std::string rb = read_file_bytes(bounced + ".json"), rd = read_file_bytes(direct + ".json");
  EXPECT_GT(test::json_number(rb, "mean_radiance"), 1.01 * test::json_number(rd, "mean_radiance"));
  EXPECT_EQ(test::json_number(rb, "reference_bounces"), 2);
  EXPECT_EQ(test::json_number(rb, "reference_albedo"), 0.6);
}

TEST_F(Cli, ColouredAlbedoBouncesAsRgbTransferThatEvalAndRenderJudgeInColour) {
  // A red plate facing down over a white ground, as OBJ vertex colours (sRGB 1 and 0 are exact);
  // the ground has UVs for the map case.
  const std::string in = dir.path("red.obj"), asset = dir.path("c.ply");
  test::write_text(in, "v -2 -2 0 1 1 1\nv 2 -2 0 1 1 1\nv 2 2 0 1 1 1\nv -2 2 0 1 1 1\n"
                       "v -1 -1 0.5 1 0 0\nv 1 -1 0.5 1 0 0\nv 1 1 0.5 1 0 0\nv -1 1 0.5 1 0 0\n"
                       "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                       "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\nf 5/1 7/3 6/2\nf 5/1 8/4 7/3\n");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--rays", "32", "--bounces", "2", "--albedo", "vertex", "--report", dir.path("b.json")}), 0);
  ASSERT_EQ(run({"inspect", asset}), 0);
  ASSERT_EQ(run({"eval", asset, "--source", in, "--points", "300", "--paths", "64", "--report", dir.path("e.json")}), 0);
  ASSERT_EQ(run({"render", asset, "--light", "const:1,1,1", "--size", "32,24", "-o", dir.path("g.png"), "--report", dir.path("g.json")}), 0);
  ASSERT_EQ(run({"render", asset, "--light", "const:1,1,1", "--reference", "--rays", "32", "--size", "32,24", "-o", dir.path("r.png")}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("coefficients per vertex, per channel: RGB transfer); albedo per vertex"), std::string::npos) << out;
  EXPECT_NE(out.find("bounced:    2 bounces at albedo vertex colours"), std::string::npos) << out;
  const Asset a = read_asset(asset);
  EXPECT_EQ(a.channels, 3);
  ASSERT_EQ(a.albedo.rows(), a.transfer.rows());
  // The plate's underside sees only the white ground: all its channels bounce alike. The ground
  // sees the red plate: its green channel gets nothing the plate did not send it.
  const Eigen::Index K = a.transfer.cols() / 3;
  double ground_red = 0, ground_green = 0;
  for (Eigen::Index v = 0; v < a.transfer.rows(); ++v)
    if (a.positions(v, 2) == 0) ground_red += a.transfer(v, 0), ground_green += a.transfer(v, K);
  EXPECT_GT(ground_red, 1.01 * ground_green);
  EXPECT_EQ(test::json_number(read_file_bytes(dir.path("e.json")), "channels"), 3);
  EXPECT_EQ(test::json_number(read_file_bytes(dir.path("b.json")), "channels"), 3);
  // Refined, so that interpolation leaves less than colour does: a grey bake of the scene judged
  // against the coloured reference (the same points, rays and paths) is further off, since its
  // green and blue carry light the red plate never sends.
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", dir.path("c3.ply"), "--rays", "32", "--bounces", "2", "--albedo", "vertex", "--refine", "uniform", "--levels", "3"}), 0);
  ASSERT_EQ(run({"bake", in, "-o", dir.path("g3.ply"), "--rays", "32", "--bounces", "2", "--albedo", "1", "--refine", "uniform", "--levels", "3"}), 0);
  ASSERT_EQ(run({"eval", dir.path("c3.ply"), "--source", in, "--points", "300", "--paths", "64", "--report", dir.path("c3.json")}), 0);
  ASSERT_EQ(run({"eval", dir.path("g3.ply"), "--source", in, "--points", "300", "--paths", "64", "--reference-albedo", "vertex",
                 "--report", dir.path("x.json")}), 0);
  testing::internal::GetCapturedStdout();
  const std::string x = read_file_bytes(dir.path("x.json")), e = read_file_bytes(dir.path("c3.json"));
  EXPECT_GT(test::json_number(x, "rms_percent"), 1.3 * test::json_number(e, "rms_percent"));
  EXPECT_EQ(test::json_number(x, "noise_floor_percent"), test::json_number(e, "noise_floor_percent"));  // one reference
  // A map through the UVs: 2 by 2 pixels, 8-bit sRGB, decoded; the asset's albedo at a vertex is
  // the map there, and eval reads the map the asset names.
  Image map;
  map.width = 2, map.height = 2, map.channels = 3;
  map.pixels = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  write_image(dir.path("m.png"), map);
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", dir.path("m.ply"), "--rays", "32", "--bounces", "1", "--albedo-map", dir.path("m.png")}), 0);
  ASSERT_EQ(run({"eval", dir.path("m.ply"), "--source", in, "--points", "200", "--paths", "32"}), 0);
  testing::internal::GetCapturedStdout();
  const Asset m = read_asset(dir.path("m.ply"));
  EXPECT_EQ(m.channels, 3);
  for (Eigen::Index v = 0; v < m.albedo.rows(); ++v)  // a corner's UV is a pixel's outer corner: the pixels' mean there (repeating)
    EXPECT_NEAR(m.albedo.row(v).sum(), 1.5, 1e-6) << v;
  // What cannot be: a grey --albedo on a coloured asset, colours the input lacks, a missing map,
  // two albedos at once.
  const size_t before = files();
  EXPECT_EQ(run({"render", asset, "--light", "sky", "--albedo", "0.5", "-o", dir.path("x.png")}), 2);
  EXPECT_EQ(run({"bake", scene(), "--albedo", "vertex", "--bounces", "1", "-o", dir.path("x.ply")}), 1);
  EXPECT_EQ(run({"bake", in, "--albedo-map", dir.path("none.png"), "--bounces", "1", "-o", dir.path("x.ply")}), 1);
  EXPECT_EQ(run({"bake", in, "--albedo", "0.8,0.5", "-o", dir.path("x.ply")}), 2);
  EXPECT_EQ(run({"bake", in, "--albedo", "0.5", "--albedo-map", dir.path("m.png"), "-o", dir.path("x.ply")}), 2);
  EXPECT_EQ(files(), before + 1);  // scene.obj, and nothing else
  testing::internal::CaptureStderr();
  run({"bake", scene(), "--albedo", "vertex", "-o", dir.path("x.ply")});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find(dir.path("scene.obj") + ": albedo from vertex colours, but the mesh has none"), std::string::npos) << err;
}

// A level of detail made elsewhere and baked as its own input: its source_face numbers its own
// faces, so eval must be told to locate the source's points by closest point.
TEST_F(Cli, EvalLocatesAnAssetBakedFromAnotherMeshByClosestPointWhenTold) {
  const std::string src = dir.path("dense.obj"), lod = dir.path("lod.obj"), asset = dir.path("lod.ply");
  const Eigen::Vector3d below(-2.5, -2.5, -1);
  test::write_obj(src, test::merge(test::icosphere(3), test::transformed(test::grid(16), 5.0, below)));
  test::write_obj(lod, test::merge(test::icosphere(2), test::transformed(test::grid(8), 5.0, below)));
  ASSERT_EQ(run({"bake", lod, "-o", asset, "--rays", "64"}), 0);
  auto rms = [&](const std::string& locate, const std::string& name) {
    testing::internal::CaptureStdout();
    EXPECT_EQ(run({"eval", asset, "--source", src, "--points", "2000", "--rays", "256", "--locate", locate, "--report", dir.path(name)}), 0);
    const std::string out = testing::internal::GetCapturedStdout();
    const std::string json = read_file_bytes(dir.path(name));
    const size_t at = json.find("\"rms_percent\": ");
    EXPECT_NE(at, std::string::npos);
    return std::make_pair(std::atof(json.c_str() + at + 15), out);
  };
  const auto [closest, closest_out] = rms("closest", "c.json");
  const auto [by_face, by_face_out] = rms("auto", "a.json");
  EXPECT_NE(closest_out.find("located by closest point\n"), std::string::npos) << closest_out;
  EXPECT_EQ(closest_out.find("warning"), std::string::npos) << closest_out;
  // The source's 1,536 faces numbered against the level of detail's 448: points beyond them have
  // no face there, and the rest land in unrelated faces.
  EXPECT_NE(by_face_out.find("had no face in the asset (baked from another mesh? --locate closest)"), std::string::npos) << by_face_out;
  EXPECT_LT(closest, 0.5 * by_face) << closest << " " << by_face;
  EXPECT_LT(closest, 6.0);  // 4.17% on this build: the level of detail's own fit error and its coarser surface
  EXPECT_EQ(run({"eval", asset, "--source", src, "--locate", "nearest"}), 2);
}

TEST_F(Cli, ABudgetBelowTheInputSimplifiesAndEvalLocatesItsPointsByClosestPoint) {
  const std::string in = dir.path("dense.obj"), asset = dir.path("s.ply");
  test::write_obj(in, test::merge(test::icosphere(2), test::transformed(test::grid(8), 5.0, Eigen::Vector3d(-2.5, -2.5, -1))));
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--rays", "16", "--refine", "adaptive", "--budget", "100", "--report", dir.path("b.json")}), 0);
  ASSERT_EQ(run({"eval", asset, "--source", in, "--points", "500", "--report", dir.path("e.json")}), 0);
  ASSERT_EQ(run({"compare", in, "--simplify", "--rays", "8", "--eval-points", "300", "--frame-size", "64,48", "--frame-rays", "4",
                 "-o", dir.path("cmp")}),
            0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("  simplify:   to the budget, metric transfer:"), std::string::npos) << out;
  EXPECT_NE(out.find("located by closest point (a simplified asset)"), std::string::npos) << out;
  const Asset a = read_asset(asset);
  EXPECT_EQ(a.triangles.size(), 100u);  // of 320 + 128 triangles
  bool simplified = false;
  for (const auto& [k, v] : a.metadata) simplified |= k == "simplified" && v.find("448 -> 100 triangles, metric transfer") == 0;
  EXPECT_TRUE(simplified);
  const std::string b = read_file_bytes(dir.path("b.json"));
  for (const char* key : {"\"simplified\": true", "\"collapses\"", "\"locked_vertices\"", "\"refused_flip\"", "\"seconds_simplify\""})
    EXPECT_NE(b.find(key), std::string::npos) << key;
  EXPECT_NE(read_file_bytes(dir.path("e.json")).find("\"location\": \"closest point"), std::string::npos);
  // compare --simplify: 50%, 25% and 10% under each metric and both ways, point and fitted, besides the
  // input's own rows (10% is out of reach of the guards on so small a mesh: 62 and 68 triangles,
  // stated by the bakes; both ways at 50% and 25% reach the count exactly).
  const std::string csv = read_file_bytes(dir.path("cmp/results.csv"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 2 + 18) << csv;
  for (const char* row : {"simplify,transfer,lsq,224,", "simplify,geometry,lsq,224,", "simplify,transfer,lsq,62,", "simplify,geometry,point,112,",
                          "auto,root,lsq,224,", "auto,root,lsq,112,"})
    EXPECT_NE(csv.find(row), std::string::npos) << row << "\n" << csv;
}

// Every usage mistake: exit 2, one line on stderr that names the option, and no file written.
TEST_F(Cli, EveryUsageMistakeExitsTwoWithOneLineNamingTheOption) {
  const std::string in = scene(), asset = dir.path("a.ply");
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--rays", "4"}), 0);
  testing::internal::GetCapturedStdout();
  const std::string out = dir.path("out.ply"), frame = dir.path("f.exr");
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"--estimate", {"bake", in, "-o", out, "--refine", "adaptive", "--budget", "100", "--estimate", "best"}},
      {"--scheme", {"bake", in, "-o", out, "--refine", "uniform", "--scheme", "x"}},
      {"--refine", {"bake", in, "-o", out, "--refine", "sideways"}},
      {"--signal", {"bake", in, "-o", out, "--signal", "light"}},
      {"--fit", {"bake", in, "-o", out, "--fit", "spline"}},
      {"--regularizer", {"bake", in, "-o", out, "--regularizer", "laplace"}},
      {"--mass", {"bake", in, "-o", out, "--mass", "lumped"}},
      {"--solver", {"bake", in, "-o", out, "--solver", "qr"}},
      {"--budget", {"bake", in, "-o", out, "--refine", "adaptive"}},
      {"--levels", {"bake", in, "-o", out, "--refine", "uniform", "--levels", "9"}},
      {"--order", {"bake", in, "-o", out, "--order", "11"}},
      {"--first-rays", {"bake", in, "-o", out, "--first-rays", "33"}},
      {"--ray-noise", {"bake", in, "-o", out, "--first-rays", "32", "--ray-noise", "-1"}},
      {"--light", {"render", asset, "--light", "moon:1", "-o", frame}},
      {"--light", {"render", asset, "--light", "sun:0,0,0", "-o", frame}},
      {"--light", {"render", asset, "--light", "sh:1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17", "-o", frame}},
      {"--camera", {"render", asset, "--light", "sky", "--camera", "eye=1,1,1", "-o", frame}},
      {"--camera", {"render", asset, "--light", "sky", "--camera", "eye=1,1,1:target=1,1,1", "-o", frame}},
      {"--light-rotate", {"render", asset, "--light", "sky", "--light-rotate", "q,3", "-o", frame}},
      {"--size", {"render", asset, "--light", "sky", "--size", "0,10", "-o", frame}},
      {"--at", {"bench", in, "--at", "edges"}},
      {"--estimates", {"compare", in, "--budgets", "300", "--estimates", "root,best", "-o", dir.path("c")}},
      {"--frame-size", {"compare", in, "--budgets", "300", "--frame-size", "1", "-o", dir.path("c")}},
      {"--light", {"compare", in, "--budgets", "300", "--light", "moon:1", "-o", dir.path("c")}},
      {"--up", {"bake", in, "-o", dir.path("x.glb"), "--up", "x"}},
      {"--quantize", {"bake", in, "-o", out, "--quantize"}},
      {"--compress", {"bake", in, "-o", out, "--compress"}},
      {"-o", {"view", asset}},
  };
  const size_t before = files();
  for (const auto& [option, args] : cases) {
    testing::internal::CaptureStderr();
    const int status = run(args);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(status, 2) << option << ": " << err;
    EXPECT_EQ(err.rfind("prtsub: error: ", 0), 0u) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find(option), std::string::npos) << option << " not named in: " << err;
  }
  EXPECT_EQ(files(), before);
}

// Every command refuses an empty asset with one line (render used to stop on an assertion).
TEST_F(Cli, EmptyAssetsAreOneLineErrorsForEveryCommand) {
  const std::string empty = dir.path("empty.ply");
  test::write_text(empty, "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
                          "property float nx\nproperty float ny\nproperty float nz\nproperty float t0\nelement face 0\n"
                          "property list uchar int vertex_indices\nproperty int source_face\nend_header\n");
  const std::string in = scene();
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"render", empty, "--light", "sky", "-o", dir.path("f.exr")}, {"inspect", empty},
        {"eval", empty, "--source", in}, {"view", empty, "-o", dir.path("v.html")}}) {
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run(args), 1) << args[0];
    testing::internal::GetCapturedStdout();
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(err, "prtsub: error: " + empty + ": empty asset (0 vertices, 0 faces)\n") << args[0];
  }
  EXPECT_FALSE(test::file_exists(dir.path("f.exr")));
  EXPECT_FALSE(test::file_exists(dir.path("v.html")));
}

// A failed check says why on stderr, not only on stdout.
TEST_F(Cli, InspectSaysOnStderrWhyItFails) {
  Mesh m = test::build(test::cube());
  m.normals *= 2;  // not unit length
  const std::string asset = dir.path("long.ply");
  write_asset(asset, m, RowMatrixXd::Ones(Eigen::Index(m.num_vertices()), 4), {});
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"inspect", asset}), 1);
  testing::internal::GetCapturedStdout();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(err, "prtsub: error: " + asset + ": " + std::to_string(m.num_vertices()) + " of " + std::to_string(m.num_vertices()) +
                     " normals are not unit length\n");
}

// What compare's page and tables take from a path is escaped for where it goes.
TEST_F(Cli, CompareEscapesTheInputsNameInItsPageAndTables) {
  const std::string in = dir.path("a<img src=x onerror=alert(1)>\"q'.obj");
  test::write_obj(in, test::merge(test::icosphere(0), test::quad(2.0, -1.0, true)));
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"compare", in, "--budgets", "200", "--max-levels", "1", "--rays", "4", "--eval-points", "200", "--estimates", "root",
                 "--frame-size", "32,24", "--frame-rays", "4", "--light", "sky:0,1,0", "-o", dir.path("c")}),
            0);
  testing::internal::GetCapturedStdout();
  const std::string html = read_file_bytes(dir.path("c/report.html")), json = read_file_bytes(dir.path("c/results.json"));
  EXPECT_EQ(html.find("<img src=x"), std::string::npos);
  EXPECT_NE(html.find("a&lt;img src=x onerror=alert(1)&gt;&quot;q&#39;.obj"), std::string::npos);
  EXPECT_EQ(json.find("<img"), std::string::npos);
  EXPECT_NE(json.find("a\\u003cimg src=x onerror=alert(1)\\u003e\\\"q'.obj"), std::string::npos) << json.substr(0, 200);
}

// Every reader of assets takes glTF: inspect, eval and render give what they give for the PLY of
// the same bake, also for a Z-up, quantized, compressed file (read back in the source's axes).
TEST_F(Cli, InspectEvalAndRenderReadGltfAssetsAsThePlyOfTheSameBake) {
  const std::string in = scene();
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", dir.path("a.ply"), "--rays", "16", "--order", "3"}), 0);
  ASSERT_EQ(run({"bake", in, "-o", dir.path("a.glb"), "--rays", "16", "--order", "3", "--up", "z", "--compress"}), 0);
  ASSERT_EQ(run({"bake", in, "-o", dir.path("q.gltf"), "--rays", "16", "--order", "3", "--quantize"}), 0);
  for (const char* name : {"a.ply", "a.glb", "q.gltf"}) {
    const std::string asset = dir.path(name), stem = std::string(name).substr(0, std::string(name).find('.')) + std::string(name).substr(std::string(name).find('.') + 1);
    ASSERT_EQ(run({"inspect", asset, "--report", dir.path(stem + "_inspect.json")}), 0) << name;
    ASSERT_EQ(run({"eval", asset, "--source", in, "--rays", "64", "--points", "2000", "--report", dir.path(stem + "_eval.json")}), 0) << name;
    ASSERT_EQ(run({"render", asset, "--light", "sky", "--size", "64,48", "-o", dir.path(stem + ".exr")}), 0) << name;
  }
  testing::internal::GetCapturedStdout();
  auto number = [&](const std::string& file, const std::string& key) {
    const std::string text = read_file_bytes(dir.path(file));
    const size_t at = text.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << file << " " << key;
    return at == std::string::npos ? NAN : std::atof(text.c_str() + at + key.size() + 4);
  };
  for (const std::string stem : {"aglb", "qgltf"}) {
    EXPECT_EQ(number(stem + "_inspect.json", "vertices"), number("aply_inspect.json", "vertices"));
    EXPECT_NEAR(number(stem + "_inspect.json", "energy_fraction_band_1"), number("aply_inspect.json", "energy_fraction_band_1"), 1e-4);
    EXPECT_NEAR(number(stem + "_eval.json", "rms_percent"), number("aply_eval.json", "rms_percent"), stem == "aglb" ? 1e-4 : 0.01);
  }
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"diff", dir.path("aglb.exr"), dir.path("aply.exr"), "--report", dir.path("diff.json")}), 0);
  testing::internal::GetCapturedStdout();
  EXPECT_LT(number("diff.json", "rmse_relative"), 1e-5);
}

// A batch is one process: every asset is the one a single bake writes, byte for byte; a bad
// input is one line on stderr and exit 1 while the others are written; a second run skips all.
TEST_F(Cli, BatchAssetsAreTheSingleBakesAndABadFileFailsAlone) {
  std::filesystem::create_directories(dir.path("in"));
  test::write_obj(dir.path("in/a.obj"), test::merge(test::icosphere(0), test::quad(2.0, -1.0, true)));
  test::write_obj(dir.path("in/b.obj"), test::cube());
  test::write_text(dir.path("in/broken.obj"), "v 0 0 0\nv 1 0 0\nv nan 0 1\nf 1 2 3\n");
  const std::vector<std::string> options = {"--rays", "16", "--order", "3"};
  auto with = [&](std::vector<std::string> args) {
    args.insert(args.end(), options.begin(), options.end());
    return args;
  };
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(run(with({"bake", dir.path("in"), "-o", dir.path("out"), "--format", "glb", "--report", dir.path("batch_report.json")})), 1);
  const std::string out = testing::internal::GetCapturedStdout(), err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(err, "prtsub: error: " + dir.path("in/broken.obj") + ": vertex 2 has a non-finite coordinate\n") << err;
  EXPECT_NE(out.find("[3/3]"), std::string::npos) << out;
  EXPECT_NE(out.find("3 assets -> " + dir.path("out") + ": 2 baked, 0 up to date, 1 failed"), std::string::npos) << out;
  testing::internal::CaptureStdout();
  for (const char* name : {"a", "b"}) {
    ASSERT_EQ(run(with({"bake", dir.path(std::string("in/") + name + ".obj"), "-o", dir.path(std::string(name) + ".glb")})), 0);
    EXPECT_EQ(read_file_bytes(dir.path(std::string("out/") + name + ".glb")), read_file_bytes(dir.path(std::string(name) + ".glb"))) << name;
    EXPECT_TRUE(test::file_exists(dir.path(std::string("out/") + name + ".report.json"))) << name;
  }
  testing::internal::GetCapturedStdout();
  const std::string csv = read_file_bytes(dir.path("out/batch.csv"));
  EXPECT_NE(csv.find(",failed,"), std::string::npos) << csv;
  EXPECT_NE(read_file_bytes(dir.path("out/batch.json")).find("\"status\": \"baked\""), std::string::npos);
  EXPECT_NE(read_file_bytes(dir.path("batch_report.json")).find("\"failed\": 1"), std::string::npos);
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(run(with({"bake", dir.path("in/a.obj"), dir.path("in/b.obj"), "-o", dir.path("out"), "--format", "glb"})), 0);
  testing::internal::GetCapturedStderr();
  EXPECT_NE(testing::internal::GetCapturedStdout().find("0 baked, 2 up to date, 0 failed"), std::string::npos);
}

// view embeds the asset and the viewer in one page; a hostile file name reaches it only escaped,
// and the asset inside is the one on disk (decoded from the page's base64 GLB).
TEST_F(Cli, ViewWritesOnePageThatHoldsTheAssetAndEscapesItsName) {
  const std::string in = scene(), asset = dir.path("a</script><img src=x onerror=alert(1)>.ply"), page = dir.path("v.html");
  std::filesystem::create_directory(dir.path("a<"));  // the path's "</" is a directory separator
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "-o", asset, "--rays", "8", "--order", "3", "--fit", "point"}), 0);
  ASSERT_EQ(run({"view", asset, "-o", page, "--source", in, "--rays", "16", "--report", dir.path("v.json")}), 0);
  testing::internal::GetCapturedStdout();
  const std::string html = read_file_bytes(page);
  EXPECT_EQ(html.find("<img src=x"), std::string::npos);
  EXPECT_NE(html.find("a&lt;/script&gt;&lt;img src=x onerror=alert(1)&gt;.ply"), std::string::npos);  // the title
  EXPECT_NE(html.find("\\u003c/script\\u003e"), std::string::npos);                                  // the data's name
  size_t scripts = 0;
  for (size_t at = html.find("</script>"); at != std::string::npos; at = html.find("</script>", at + 1)) ++scripts;
  EXPECT_EQ(scripts, 2u) << "the data and the bundle, each closed once";
  const size_t glb = html.find("\"glb\":\"") + 7;
  const std::string bytes = test::base64_decode(html.substr(glb, html.find('"', glb) - glb));
  const Asset inside = parse_asset(bytes, "page"), original = read_asset(asset);
  EXPECT_EQ(inside.transfer, original.transfer);
  EXPECT_EQ(inside.triangles, original.triangles);
  const std::string report = read_file_bytes(dir.path("v.json"));
  EXPECT_NE(report.find("\"reference_rays\": 16"), std::string::npos) << report;
  EXPECT_NE(html.find("\"error\":{\"segments\":"), std::string::npos);
}

}  // namespace
}  // namespace prtsub

namespace prtsub {
namespace {

TEST(CliEstimator, TheEstimatorIsChosenReportedAndRecordedInTheAsset) {
  test::TempDir dir;
  const std::string in = dir.path("scene.obj"), out = dir.path("a.ply"), rep = dir.path("r.json");
  test::write_obj(in, test::merge(test::icosphere(1), test::quad(3.0, -1.0, true)));
  ASSERT_EQ(test::run_prtsub({"bake", in, "-o", out, "--fit", "point", "--rays", "16", "--estimator", "pls-cv", "--pls-update", "jacobi",
                              "--report", rep}),
            0);
  EXPECT_NE(read_file_bytes(rep).find("\"estimator\": \"pls-cv\""), std::string::npos);
  bool recorded = false;
  for (const auto& [k, v] : read_asset(out).metadata)
    recorded |= k == "estimator" && v.find("progressive least-squares (Roughton 2020) of the blocked part, Jacobi") == 0;
  EXPECT_TRUE(recorded);
  // The default's record is unchanged; a bad name is one line and exit 2 with nothing written.
  ASSERT_EQ(test::run_prtsub({"bake", in, "-o", out, "--fit", "point", "--rays", "16", "--report", rep}), 0);
  EXPECT_NE(read_file_bytes(rep).find("\"estimator\": \"cv\""), std::string::npos);
  const std::string none = dir.path("none.ply");
  EXPECT_NE(test::run_prtsub({"bake", in, "-o", none, "--estimator", "lsq"}), 0);
  EXPECT_FALSE(std::filesystem::exists(none));
}

}  // namespace
}  // namespace prtsub
