// Batches: the content key covers every option that changes an asset (and not the thread
// count), a bad file fails alone, an up-to-date asset is skipped, and jobs come from files,
// folders and lists with no two writing one asset.
#include "prtsub/prt/batch.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <set>

#include "helpers.h"
#include "prtsub/prt/asset.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {
namespace fs = std::filesystem;

TEST(Batch, TheKeyChangesWithEveryOptionThatChangesTheAssetAndNotWithThreads) {
  const std::string bytes = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const BatchOptions base;
  const std::string k0 = bake_key(bytes, base, "a.ply");
  EXPECT_EQ(k0.size(), 32u);
  EXPECT_EQ(bake_key(bytes, base, "a.ply"), k0) << "a function of its inputs";
  EXPECT_EQ(bake_key(bytes, base, "elsewhere/b.ply"), k0) << "the name of the output is not the asset";
  BatchOptions threads = base;
  threads.bake.transfer.threads = 1, threads.bake.fit.threads = 1;
  EXPECT_EQ(bake_key(bytes, threads, "a.ply"), k0) << "results do not depend on the thread count";
  const std::vector<std::pair<const char*, std::function<void(BatchOptions&)>>> changes = {
      {"order", [](BatchOptions& o) { o.bake.transfer.order = 3; }},
      {"order_auto", [](BatchOptions& o) { o.bake.order_auto = true; }},
      {"bounce_fit_samples", [](BatchOptions& o) { o.bake.bounce.bounces = 1, o.bake.bounce.fit_samples = false; }},
      {"max_order", [](BatchOptions& o) { o.bake.order_choice.max_order = 6; }},
      {"order_tolerance", [](BatchOptions& o) { o.bake.order_choice.tolerance_percent = 2; }},
      {"order_light", [](BatchOptions& o) { o.bake.order_choice.band_power = {1, 0.5}; }},
      {"rays", [](BatchOptions& o) { o.bake.transfer.rays = 128; }},
      {"seed", [](BatchOptions& o) { o.bake.transfer.seed = 1; }},
      {"signal", [](BatchOptions& o) { o.bake.signal = AssetSignal::Ao; }},
      {"refine", [](BatchOptions& o) { o.bake.refine = Refinement::Uniform; }},
      {"budget", [](BatchOptions& o) { o.bake.adaptive.budget = 10; }},
      {"batch", [](BatchOptions& o) { o.bake.adaptive.batch = 7; }},
      {"max_edge", [](BatchOptions& o) { o.bake.adaptive.max_edge = 0.5; }},
      {"estimate", [](BatchOptions& o) { o.bake.estimate = EdgeEstimate::Length; }},
      {"levels", [](BatchOptions& o) { o.bake.uniform.levels = 2; }},
      {"scheme", [](BatchOptions& o) { o.bake.uniform.scheme = UniformScheme::Loop; }},
      {"fit", [](BatchOptions& o) { o.bake.fit.method = FitMethod::Point; }},
      {"alpha", [](BatchOptions& o) { o.bake.fit.alpha = 0.05; }},
      {"regularizer", [](BatchOptions& o) { o.bake.fit.regularizer = Regularizer::Gradient; }},
      {"mass", [](BatchOptions& o) { o.bake.fit.mass = MassMatrix::Sampled; }},
      {"control_variate", [](BatchOptions& o) { o.bake.fit.control_variate = false; }},
      {"solver", [](BatchOptions& o) { o.bake.fit.solver = FitSolver::Cholmod; }},
      {"cg_tolerance", [](BatchOptions& o) { o.bake.fit.cg_tolerance = 1e-8; }},
      {"cg_max_iterations", [](BatchOptions& o) { o.bake.fit.cg_max_iterations = 50; }},
      {"weigh_by_noise", [](BatchOptions& o) { o.bake.fit.weigh_by_noise = false; }},
      {"unshadowed_projection", [](BatchOptions& o) { o.bake.unshadowed_projection = false; }},
      {"alpha_auto", [](BatchOptions& o) { o.bake.alpha_auto = false; }},
      {"rays_auto", [](BatchOptions& o) { o.bake.rays_auto = true; }},
      {"alpha_choices", [](BatchOptions& o) { o.bake.alpha_choices = {0, 0.1, 1}; }},
      {"non_negative", [](BatchOptions& o) { o.bake.fit.non_negative = NonNegative::Off; }},
      {"per_triangle", [](BatchOptions& o) { o.bake.samples.per_triangle = 8; }},
      {"density", [](BatchOptions& o) { o.bake.samples.density = 3; }},
      {"min_per_triangle", [](BatchOptions& o) { o.bake.samples.min_per_triangle = 2; }},
      {"allocation", [](BatchOptions& o) { o.bake.allocation = SampleAllocation::Area; }},
      {"pilot per_triangle", [](BatchOptions& o) { o.bake.pilot.per_triangle = 3; }},
      {"pilot min_samples", [](BatchOptions& o) { o.bake.pilot.min_samples = 100; }},
      {"pilot rays", [](BatchOptions& o) { o.bake.pilot.rays = 16; }},
      {"pilot rings", [](BatchOptions& o) { o.bake.pilot.rings = 1; }},
      {"pilot significance", [](BatchOptions& o) { o.bake.pilot.significance = 3; }},
      {"pilot area_share", [](BatchOptions& o) { o.bake.pilot.area_share = 0.25; }},
      {"pilot holdout", [](BatchOptions& o) { o.bake.pilot.holdout = 1000; }},
      {"pilot first_share", [](BatchOptions& o) { o.bake.pilot.first_share = 0.25; }},
      {"pilot first_significance", [](BatchOptions& o) { o.bake.pilot.first_significance = 2; }},
      {"vertex_share", [](BatchOptions& o) { o.bake.vertex_share = 0.25; }},
      {"target_error", [](BatchOptions& o) { o.bake.target_error = 1.5; }},
      {"sample_rays", [](BatchOptions& o) { o.bake.sample_rays = 8; }},
      {"bounces", [](BatchOptions& o) { o.bake.bounce.bounces = 2; }},
      {"bounces auto", [](BatchOptions& o) { o.bake.bounce.until_converged = true; }},
      {"albedo", [](BatchOptions& o) { o.bake.bounce.albedo = 0.5; }},
      {"simplify metric", [](BatchOptions& o) { o.bake.simplify.metric = SimplifyMetric::Geometry; }},
      {"geometry weight", [](BatchOptions& o) { o.bake.simplify.geometry_weight = 10; }},
      {"min angle", [](BatchOptions& o) { o.bake.simplify.min_angle_deg = 2; }},
      {"feature tolerance", [](BatchOptions& o) { o.bake.simplify.feature_tolerance = 1e-2; }},
      {"surface tolerance", [](BatchOptions& o) { o.bake.simplify.surface_tolerance = 1e-2; }},
      {"max surface tolerance", [](BatchOptions& o) { o.bake.simplify.max_surface_tolerance = 0.1; }},
      {"simplified alpha", [](BatchOptions& o) { o.bake.simplified_alpha = 0.01; }},
      {"stage", [](BatchOptions& o) { o.bake.refine_only = true; }},
      {"auto share", [](BatchOptions& o) { o.bake.auto_share = 0.25; }},
      {"auto cycles", [](BatchOptions& o) { o.bake.auto_cycles = 0; }},
      {"auto cycle share", [](BatchOptions& o) { o.bake.auto_cycle_share = 0.03; }},
      {"crease angle", [](BatchOptions& o) { o.load.crease_angle_deg = 30; }},
      {"up", [](BatchOptions& o) { o.gltf.up = UpAxis::Z; }},
      {"quantize", [](BatchOptions& o) { o.gltf.quantize = true; }},
      {"compress", [](BatchOptions& o) { o.gltf.compress = true; }},
  };
  std::set<std::string> keys = {k0};
  for (const auto& [name, change] : changes) {
    BatchOptions o = base;
    change(o);
    EXPECT_TRUE(keys.insert(bake_key(bytes, o, "a.ply")).second) << name << " does not change the key";
  }
  EXPECT_TRUE(keys.insert(bake_key(bytes, base, "a.glb")).second) << "the format";
  EXPECT_TRUE(keys.insert(bake_key(bytes + " ", base, "a.ply")).second) << "the input's bytes";
}

class BatchRun : public ::testing::Test {
 protected:
  test::TempDir dir;
  BatchOptions options;
  void SetUp() override {
    options.bake.transfer.rays = 16, options.bake.transfer.order = 2, options.bake.fit.method = FitMethod::Point;
    fs::create_directories(dir.path("in/sub"));
    test::write_obj(dir.path("in/a.obj"), test::merge(test::icosphere(0), test::quad(2.0, -1.0, true)));
    test::write_text(dir.path("in/bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n");
    test::write_obj(dir.path("in/sub/c.obj"), test::cube());
    test::write_text(dir.path("in/sub/readme.txt"), "not a mesh");
  }
};

TEST_F(BatchRun, OneBadFileFailsAloneAndAnUpToDateAssetIsSkipped) {
  const std::vector<BatchJob> jobs = batch_jobs({dir.path("in")}, dir.path("out"), ".ply");
  ASSERT_EQ(jobs.size(), 3u);  // a.obj, bad.obj, sub/c.obj, in name order; readme.txt is no mesh
  EXPECT_EQ(jobs[2].output, dir.path("out") + "/sub/c.ply");
  std::vector<BatchEntry> e = bake_batch(jobs, options);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0].status, BatchStatus::Baked);
  EXPECT_EQ(e[1].status, BatchStatus::Failed);
  EXPECT_EQ(e[1].error, dir.path("in/bad.obj") + ": face 0 refers to vertex 8, but the file has 2 vertices (0-based)");
  EXPECT_FALSE(test::file_exists(jobs[1].output));
  EXPECT_EQ(e[2].status, BatchStatus::Baked);
  EXPECT_EQ(asset_bake_key(jobs[0].output), e[0].key);
  const std::string a = read_file_bytes(jobs[0].output), c = read_file_bytes(jobs[2].output);

  e = bake_batch(jobs, options);  // again: both up to date, nothing written
  EXPECT_EQ(e[0].status, BatchStatus::Skipped);
  EXPECT_EQ(e[2].status, BatchStatus::Skipped);
  EXPECT_EQ(read_file_bytes(jobs[0].output), a);

  test::write_obj(dir.path("in/sub/c.obj"), test::transformed(test::cube(), 2.0, Eigen::Vector3d::Zero()));  // one input changes
  e = bake_batch(jobs, options);
  EXPECT_EQ(e[0].status, BatchStatus::Skipped);
  EXPECT_EQ(e[2].status, BatchStatus::Baked);
  EXPECT_NE(read_file_bytes(jobs[2].output), c);

  options.bake.transfer.rays = 32;  // an option changes: every asset is stale
  e = bake_batch(jobs, options);
  EXPECT_EQ(e[0].status, BatchStatus::Baked);
  EXPECT_EQ(e[2].status, BatchStatus::Baked);
  options.force = true;
  EXPECT_EQ(bake_batch(jobs, options)[0].status, BatchStatus::Baked);
}

TEST_F(BatchRun, JobsComeFromFilesFoldersAndListsAndNeverShareAnOutput) {
  test::write_text(dir.path("in/list.txt"), "# the props\n\na.obj\n  sub/c.obj  \n" + dir.path("in/bad.obj") + "\n");
  const std::vector<BatchJob> jobs = batch_jobs({"@" + dir.path("in/list.txt")}, dir.path("out"), ".glb");
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].input, dir.path("in") + "/a.obj");
  EXPECT_EQ(jobs[1].output, dir.path("out") + "/c.glb");
  EXPECT_EQ(jobs[2].input, dir.path("in/bad.obj"));
  try {
    batch_jobs({dir.path("in/a.obj"), dir.path("in")}, dir.path("out"), ".ply");  // a.obj twice
    ADD_FAILURE() << "two jobs wrote one asset";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("would both write " + dir.path("out") + "/a.ply"), std::string::npos) << e.what();
  }
  EXPECT_THROW(batch_jobs({dir.path("in/none.obj")}, dir.path("out"), ".ply"), IoError);
  EXPECT_THROW(batch_jobs({dir.path("in")}, dir.path("out"), ".obj"), InputError);
}

}  // namespace
}  // namespace prtsub
