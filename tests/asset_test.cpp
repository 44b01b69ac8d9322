#include "prtsub/prt/asset.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "helpers.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

RowMatrixXd ramp(const Mesh& m, int K) {
  RowMatrixXd t(static_cast<Eigen::Index>(m.num_vertices()), K);
  for (Eigen::Index v = 0; v < t.rows(); ++v)
    for (int c = 0; c < K; ++c) t(v, c) = 0.25 * static_cast<double>(v) - 0.125 * c;
  return t;
}

TEST(Asset, RoundTripsEveryField) {
  test::TempDir dir;
  Mesh m = test::build(test::cube());
  RowMatrixXd t = ramp(m, 9);
  Metadata meta = sh_convention_metadata(3);
  meta.push_back({"rays", "64"});
  write_asset(dir.path("a.ply"), m, t, meta);
  Asset a = read_asset(dir.path("a.ply"));
  EXPECT_EQ(a.order, 3);
  ASSERT_EQ(a.transfer.rows(), static_cast<Eigen::Index>(m.num_vertices()));
  EXPECT_EQ((a.transfer - t).cwiseAbs().maxCoeff(), 0.0);  // values chosen exact in float
  EXPECT_LT((a.normals - m.normals).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_EQ(a.triangles, m.triangles);
  EXPECT_EQ(a.source_face, m.source_face);
  for (size_t v = 0; v < m.num_vertices(); ++v)
    EXPECT_EQ((a.positions.row(static_cast<Eigen::Index>(v)) - m.positions.row(m.vertex_position[v])).norm(), 0.0);
  ASSERT_GE(a.metadata.size(), 5u);
  EXPECT_EQ(a.metadata[2].first, "sh_order");
  EXPECT_EQ(a.metadata[2].second, "3");
  EXPECT_EQ(a.metadata.back().second, "64");
  // Header declares exactly the documented properties, in order.
  PlyFile ply = read_ply(dir.path("a.ply"));
  EXPECT_EQ(ply.format, "binary_little_endian");
  std::vector<std::string> expect = {"x", "y", "z", "nx", "ny", "nz"};
  for (int c = 0; c < 9; ++c) expect.push_back("t" + std::to_string(c));
  EXPECT_EQ(ply.element("vertex")->scalar_names, expect);
  EXPECT_EQ(ply.element("face")->scalar_names, std::vector<std::string>{"source_face"});
}

TEST(Asset, TheBouncesAnAssetFoldsInAreReadFromItsMetadata) {
  Asset a;
  EXPECT_EQ(asset_bounces(a, "a.ply").bounces, 0);
  a.metadata = {{"bounces", "3 (albedo 0.55; the last pass added 1.2% of ||t_unshadowed||)"}};
  const AssetBounces b = asset_bounces(a, "a.ply");
  EXPECT_EQ(b.bounces, 3);
  EXPECT_EQ(b.albedo, 0.55);
  for (const char* bad : {"three (albedo 0.5)", "3", "3 (albedo 1.5)", "-1 (albedo 0.5)", "65 (albedo 0.5)", "2 (albedo nan)"}) {
    a.metadata = {{"bounces", bad}};
    try {
      asset_bounces(a, "a.ply");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("a.ply: ", 0), 0u) << e.what();
    }
  }
}

TEST(Asset, UvsAreWrittenAfterTheNormalsOnlyWhenTheMeshHasThem) {
  test::TempDir dir;
  Mesh m = build_mesh(parse_obj(test::seam_square_obj(), "seam.obj"), "seam.obj");
  ASSERT_TRUE(m.has_uv());
  write_asset(dir.path("uv.ply"), m, ramp(m, 4), sh_convention_metadata(2));
  Asset a = read_asset(dir.path("uv.ply"));
  ASSERT_EQ(a.uv.rows(), m.uv.rows());
  EXPECT_LT((a.uv - m.uv).cwiseAbs().maxCoeff(), 1e-7);  // float32
  std::vector<std::string> expect = {"x", "y", "z", "nx", "ny", "nz", "u", "v", "t0", "t1", "t2", "t3"};
  EXPECT_EQ(read_ply(dir.path("uv.ply")).element("vertex")->scalar_names, expect);
  // A mesh without UVs: no u v properties at all.
  Mesh cube = test::build(test::cube());
  write_asset(dir.path("plain.ply"), cube, ramp(cube, 4), sh_convention_metadata(2));
  EXPECT_EQ(read_asset(dir.path("plain.ply")).uv.rows(), 0);
  // Non-finite UVs are refused, and nothing is written.
  m.uv(0, 1) = NAN;
  EXPECT_THROW(write_asset(dir.path("bad.ply"), m, ramp(m, 4), sh_convention_metadata(2)), InputError);
  EXPECT_FALSE(test::file_exists(dir.path("bad.ply")));
}

TEST(Asset, NonFiniteTransferIsRefusedAndLeavesNoFile) {
  test::TempDir dir;
  Mesh m = test::build(test::cube());
  RowMatrixXd t = ramp(m, 4);
  t(3, 2) = std::nan("");
  EXPECT_THROW(write_asset(dir.path("nan.ply"), m, t, {}), InputError);
  EXPECT_FALSE(test::file_exists(dir.path("nan.ply")));
  t(3, 2) = 1e39;  // finite in double, infinite in float
  EXPECT_THROW(write_asset(dir.path("big.ply"), m, t, {}), InputError);
  EXPECT_FALSE(test::file_exists(dir.path("big.ply")));
  EXPECT_TRUE(std::filesystem::is_empty(std::filesystem::path(dir.path(""))));
}

TEST(Asset, ReaderRejectsCorruptAssets) {
  test::TempDir dir;
  Mesh m = test::build(test::cube());
  write_asset(dir.path("ok.ply"), m, ramp(m, 4), {});
  std::string bytes = read_file_bytes(dir.path("ok.ply"));
  // NaN in a transfer value.
  std::string nan = bytes;
  size_t body = nan.find("end_header\n") + 11;
  float q = std::nanf("");
  std::memcpy(&nan[body + 4 * 7], &q, 4);  // vertex 0, t1
  test::write_text(dir.path("nan.ply"), nan);
  EXPECT_THROW(read_asset(dir.path("nan.ply")), InputError);
  // Truncated.
  test::write_text(dir.path("cut.ply"), bytes.substr(0, bytes.size() - 3));
  EXPECT_THROW(read_asset(dir.path("cut.ply")), InputError);
  // Out-of-range face index.
  std::string idx = bytes;
  int32_t big = 1000;
  std::memcpy(&idx[bytes.size() - 16], &big, 4);
  test::write_text(dir.path("idx.ply"), idx);
  EXPECT_THROW(read_asset(dir.path("idx.ply")), InputError);
  // A mesh without transfer is not an asset.
  test::write_text(dir.path("mesh.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                         "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                                         "element face 1\nproperty list uchar int vertex_indices\nproperty int source_face\n"
                                         "end_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2 0\n");
  EXPECT_THROW(read_asset(dir.path("mesh.ply")), InputError);
}

TEST(Asset, EmptyAssetsAndNonIntegralIndicesAreOneLineErrors) {
  test::TempDir dir;
  const std::string header = "ply\nformat ascii 1.0\ncomment prtsub_asset 1\nelement vertex %d\nproperty float x\nproperty float y\n"
                             "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float t0\n"
                             "element face %d\nproperty list uchar int vertex_indices\nproperty float source_face\nend_header\n";
  auto asset = [&](int v, int f, const std::string& body) {
    char h[1024];
    std::snprintf(h, sizeof h, header.c_str(), v, f);
    test::write_text(dir.path("a.ply"), h + body);
    try {
      read_asset(dir.path("a.ply"));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(asset(0, 0, "").find("empty asset (0 vertices, 0 faces)"), std::string::npos);
  const std::string three = "0 0 0 0 0 1 1\n1 0 0 0 0 1 1\n0 1 0 0 0 1 1\n";
  EXPECT_NE(asset(3, 0, three).find("empty asset"), std::string::npos);
  EXPECT_EQ(asset(3, 1, three + "3 0 1 2 0\n"), "(accepted)");
  EXPECT_NE(asset(3, 1, three + "3 0 1 2 2.5\n").find("source_face is not an integer index"), std::string::npos);
  EXPECT_NE(asset(3, 1, three + "3 0 1 2 nan\n").find("source_face is not an integer index"), std::string::npos);
  EXPECT_NE(asset(3, 1, three + "3 0 1 2 1e300\n").find("source_face is not an integer index"), std::string::npos);
  EXPECT_NE(asset(3, 1, three + "3 0 1 2 -1\n").find("out of range"), std::string::npos);
}

// Found by tests/fuzz (fuzz_asset, 2026-11-29): a vertex element claiming 26,666,666,665 rows
// and no properties, so no bytes bounded the claim, and the asset's arrays were sized by it
// (out of memory). Now an InputError before anything is allocated.
TEST(Asset, FuzzFindingAClaimedCountWithoutPropertiesIsAnError) {
  const std::string bytes = test::base64_decode(
      "cGx5CmZvcm1hdCBiaW5hcnlfbGl0dGxlX2VuZGlhbiAyLjAKY29tbWVudCBjb21tZW50IHNoX29yZGVyIDAKZWxlbWVudCB2ZXJ0ZXggMjY2NjY2NjY2"
      "NjVgAGkgMS5YCmVsZW1lbnQgZmFjZSAxZ2VfZmFjZQplbmRfaGVhZGVyCgAA0OUAAD9iPwMA");
  ASSERT_EQ(bytes.substr(0, 4), "ply\n");
  try {
    parse_asset(bytes, "crash.ply");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("declares 26666666665 rows but no properties"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace prtsub
