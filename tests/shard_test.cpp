// Sharded bakes: every shard count gives the one-process bake bit for bit, the phases are the
// ones shard_phases() promises, and parts that do not belong together are refused by name.
#include "prtsub/prt/shard.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "helpers.h"
#include "prtsub/prt/trace_log.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

Mesh sphere_on_plane() { return test::build(test::merge(test::icosphere(2), test::quad(2.5, -1.0, true))); }

BakeOptions small_bake() {
  BakeOptions o;
  o.transfer.rays = 32, o.sample_rays = 4, o.samples.per_triangle = 8;
  o.pilot.rays = 8, o.pilot.min_samples = 512;
  return o;
}

// Every phase of every shard (threads varying from shard to shard), then the merge.
BakeResult sharded(const Mesh& mesh, const BakeOptions& o, uint32_t shards, const std::string& dir, int* phases_traced = nullptr) {
  ShardOptions s;
  s.shards = shards, s.dir = dir, s.key = "k";
  int traced = 0;
  for (int phase = 1;; ++phase) {
    bool any = false;
    for (uint32_t i = 1; i <= shards; ++i) {
      s.shard = i;
      BakeOptions oi = o;
      oi.transfer.threads = 1 + int(i % 2);
      const ShardResult r = bake_shard(mesh, oi, s);
      if (r.nothing_left) continue;
      EXPECT_EQ(r.phase, phase);
      any = true;
    }
    if (!any) break;
    ++traced;
  }
  if (phases_traced) *phases_traced = traced;
  return bake_merged(mesh, o, dir, "k");
}

void expect_identical(const BakeResult& a, const BakeResult& b) {
  ASSERT_EQ(a.transfer.rows(), b.transfer.rows());
  EXPECT_EQ(std::memcmp(a.transfer.data(), b.transfer.data(), sizeof(double) * size_t(a.transfer.size())), 0) << "not bit-identical";
  EXPECT_EQ(std::memcmp(a.point.data(), b.point.data(), sizeof(double) * size_t(a.point.size())), 0);
  EXPECT_EQ(a.rays, b.rays);
  EXPECT_EQ(a.metadata, b.metadata);
}

TEST(Shard, AnyShardCountMergesToTheOneProcessBakeBitForBit) {
  const Mesh mesh = sphere_on_plane();
  const BakeOptions o = small_bake();
  const BakeResult one = bake(mesh, o);
  ASSERT_GT(one.fit_data.plan.sampled_faces, 0u) << "the pilot must choose faces, or its phases test nothing";
  ASSERT_GT(one.top_up.vertices, 0u) << "the top-up must run, or its slices test nothing";
  // 1, 3 and more shards than some calls have points (the pilot's second stage): empty slices.
  for (uint32_t n : {1u, 3u, 200u}) {
    test::TempDir dir;
    int phases = 0;
    const BakeResult merged = sharded(mesh, o, n, dir.path("parts"), &phases);
    EXPECT_EQ(phases, 4) << n;  // the pilot's screen, its two stages, the top-up
    expect_identical(one, merged);
  }
}

TEST(Shard, PhasesAreTheOnesShardPhasesPromisesForEachPipeline) {
  const Mesh mesh = sphere_on_plane();
  struct Case {
    const char* name;
    void (*change)(BakeOptions&);
    int phases;
  };
  const Case cases[] = {
      {"point values", [](BakeOptions& o) { o.fit.method = FitMethod::Point; }, 1},
      {"area samples", [](BakeOptions& o) { o.allocation = SampleAllocation::Area; }, 1},
      {"one-stage pilot", [](BakeOptions& o) { o.pilot.first_share = 1; }, 3},
      {"no screen", [](BakeOptions& o) { o.pilot.screen_ratio = 0; }, 3},
      // The screen stops the pilot: its stages' phases pass with nothing traced in them.
      {"pilot stopped by its screen", [](BakeOptions& o) { o.pilot.screen_ratio = 1e6; }, 4},
      {"ambient occlusion", [](BakeOptions& o) { o.signal = AssetSignal::Ao; }, 4},
      {"error target and bounces (the merge's)", [](BakeOptions& o) { o.target_error = 0.3, o.bounce.bounces = 1; }, 4},
  };
  for (const Case& c : cases) {
    BakeOptions o = small_bake();
    c.change(o);
    EXPECT_EQ(shard_phases(o), c.phases) << c.name;
    test::TempDir dir;
    int phases = 0;
    const BakeResult merged = sharded(mesh, o, 2, dir.path("parts"), &phases);
    EXPECT_EQ(phases, c.phases) << c.name;
    expect_identical(bake(mesh, o), merged);
  }
}

TEST(Shard, APartsFolderThatDoesNotAddUpIsRefusedNamingTheFile) {
  const Mesh mesh = sphere_on_plane();
  BakeOptions o = small_bake();
  o.allocation = SampleAllocation::Area;  // one phase
  test::TempDir dir;
  const std::string parts = dir.path("parts");
  ShardOptions s;
  s.shards = 3, s.dir = parts, s.key = "k";
  auto message = [&](auto&& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  auto merge = [&] { bake_merged(mesh, o, parts, "k"); };
  for (uint32_t i : {1u, 3u}) s.shard = i, bake_shard(mesh, o, s);
  EXPECT_NE(message(merge).find("phase 1 lacks shard 2 of 3 (phase1-shard2of3.part)"), std::string::npos) << message(merge);
  s.shard = 2, bake_shard(mesh, o, s);
  EXPECT_NO_THROW(merge());

  namespace fs = std::filesystem;
  fs::copy_file(parts + "/phase1-shard2of3.part", parts + "/again.part");
  EXPECT_NE(message(merge).find("are both phase 1's shard 2 of 3"), std::string::npos) << message(merge);
  fs::remove(parts + "/again.part");

  // Another bake's key, another shard count: refused before anything is read.
  EXPECT_NE(message([&] { bake_merged(mesh, o, parts, "other"); }).find("a part of another bake"), std::string::npos);
  ShardOptions four = s;
  four.shards = 4, four.shard = 1;
  EXPECT_NE(message([&] { bake_shard(mesh, o, four); }).find("a part of a bake in 3 shards, not 4"), std::string::npos);

  // The same key but another mesh (a caller that keyed by name): the calls' fingerprints differ.
  const Mesh other = test::build(test::merge(test::icosphere(1), test::quad(2.5, -1.0, true)));
  EXPECT_NE(message([&] { bake_merged(other, o, parts, "k"); }).find("traced for another bake"), std::string::npos);

  // A flipped byte in the values, a cut-short file.
  const std::string victim = parts + "/phase1-shard3of3.part";
  std::string bytes = read_file_bytes(victim);
  bytes[bytes.size() - 5] ^= 0x40;
  test::write_text(victim, bytes);
  EXPECT_NE(message(merge).find("phase1-shard3of3.part: damaged part: its values do not match its checksum"), std::string::npos)
      << message(merge);
  test::write_text(victim, bytes.substr(0, bytes.size() - 8));
  EXPECT_NE(message(merge).find("damaged part: "), std::string::npos) << message(merge);
  test::write_text(victim, "prtsub part 1\nkey k\n");
  EXPECT_NE(message(merge).find("its header has no end"), std::string::npos) << message(merge);
  test::write_text(victim, "a mesh, not a part\n");
  EXPECT_NE(message(merge).find("not a prtsub part"), std::string::npos) << message(merge);

  // A fixed mesh only: adaptive refinement is one queue.
  BakeOptions adaptive = o;
  adaptive.refine = Refinement::Adaptive, adaptive.adaptive.budget = 2000;
  EXPECT_NE(message([&] { bake_shard(mesh, adaptive, s); }).find("needs a fixed mesh"), std::string::npos);
}

TEST(Shard, ShardTextIsOneBasedAndBounded) {
  EXPECT_EQ(parse_shard("1/1"), std::make_pair(1u, 1u));
  EXPECT_EQ(parse_shard("7/64"), std::make_pair(7u, 64u));
  for (const char* bad : {"0/4", "5/4", "4", "/4", "1/", "a/b", "-1/4", "1/70000", "1/4x", "+1/4"})
    EXPECT_THROW(parse_shard(bad), InputError) << bad;
}

TEST(Shard, AStopAfterRefinementKeepsTheRefinedMeshAndItsPointValues) {
  const Mesh mesh = sphere_on_plane();
  BakeOptions o = small_bake();
  o.refine = Refinement::Adaptive, o.adaptive.budget = 1500;
  BakeOptions stop = o, point = o;
  stop.refine_only = true;
  point.fit.method = FitMethod::Point;
  const BakeResult full = bake(mesh, point), refined = bake(mesh, stop);
  EXPECT_EQ(refined.mesh.num_faces(), 1500u);
  EXPECT_EQ(refined.mesh.triangles, full.mesh.triangles) << "the same refinement";
  EXPECT_EQ(refined.fit_data.samples.size(), 0u) << "no samples, no fit";
  EXPECT_EQ(std::memcmp(refined.transfer.data(), full.transfer.data(), sizeof(double) * size_t(full.transfer.size())), 0)
      << "the refined mesh's point values";
  bool staged = false;
  for (const auto& [k, v] : refined.metadata) staged |= k == "stage";
  EXPECT_TRUE(staged) << "the asset says it is a refinement stage";
}

}  // namespace
}  // namespace prtsub
