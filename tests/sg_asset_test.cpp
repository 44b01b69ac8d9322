// Spherical-Gaussian assets end to end (issue 15, point 3): the bake, the file, and relighting.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "cli_helpers.h"
#include "helpers.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/gltf.h"
#include "prtsub/prt/render.h"
#include "prtsub/prt/sg_basis.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

// A sphere resting above a plane: open sky on top, a contact shadow beneath.
Mesh sphere_on_plane() { return test::build(test::merge(test::icosphere(2), test::quad(3.0, -1.05, true))); }

BakeOptions lobe_options(int lobes, int rays = 128) {
  BakeOptions o;
  o.sg_lobes = lobes;
  o.fit.method = FitMethod::Point;
  o.transfer.rays = rays;
  return o;
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? s : s.replace(at, from.size(), to);
}

TEST(SgAsset, ReadBackItRelightsAsItsLobesDoUnderAnyLight) {
  // The file keeps the lobes; the asset read back relights them through their SH equivalent at
  // sg_shading_order. Against the closed form (albedo/π) Σ c_k L_k with L_k = sg_light: equal for
  // every light of that order, and within the 0.1% the order promises for an order-10 light.
  test::TempDir dir;
  const Mesh m = sphere_on_plane();
  for (int lobes : {9, 12}) {
    const BakeResult r = bake(m, lobe_options(lobes));
    ASSERT_EQ(r.transfer.cols(), lobes);
    EXPECT_GE(r.transfer.minCoeff(), 0.0);  // non-negative by default
    const std::string path = dir.path("sg" + std::to_string(lobes) + ".ply");
    write_asset(path, r.mesh, r.transfer, r.metadata);
    const Asset a = read_asset(path);
    const SgBasis basis = sg_basis(lobes);
    ASSERT_EQ(a.sg.cols(), lobes);
    EXPECT_EQ(a.order, sg_shading_order(basis));
    EXPECT_LT((a.sg - r.transfer).cwiseAbs().maxCoeff(), 1e-6 * r.transfer.cwiseAbs().maxCoeff());  // float32
    EXPECT_EQ(&stored_values(a), &a.sg);
    for (uint64_t seed : {1, 2, 3}) {
      const ShLight light = random_light(a.order, seed);
      const RowMatrixX3d through_sh = vertex_radiance(a.transfer, light, 0.8);
      const RowMatrixX3d closed = (0.8 / M_PI) * (a.sg * sg_light(basis, light));
      EXPECT_LT((through_sh - closed).cwiseAbs().maxCoeff(), 1e-10 * (1 + closed.cwiseAbs().maxCoeff())) << lobes << " " << seed;
      // A light with bands above the order: what reaches the lobes from there is at most 0.1% of
      // each lobe's norm times the light's, summed over the lobes.
      const ShLight high = random_light(kMaxShOrder, seed);
      const RowMatrixX3d truncated = vertex_radiance(a.transfer, high, 0.8);
      const RowMatrixX3d exact = (0.8 / M_PI) * (a.sg * sg_light(basis, high));
      const double lobe_norm = std::sqrt(sg_gram(basis)(0, 0)), bound = 1e-3 * lobe_norm * high.coeffs.col(0).norm();
      for (Eigen::Index v = 0; v < a.sg.rows(); v += 37)
        EXPECT_LE(std::abs(truncated(v, 0) - exact(v, 0)), (0.8 / M_PI) * bound * a.sg.row(v).sum() + 1e-12) << lobes << " " << v;
    }
  }
}

TEST(SgAsset, TheShadingOrderHoldsTheLobesBandsAsDocumented) {
  // sg_basis.h: 8 for 9 lobes, 10 for 12 and 16; and it is the lowest order that holds them.
  EXPECT_EQ(sg_shading_order(sg_basis(9)), 8);
  EXPECT_EQ(sg_shading_order(sg_basis(12)), 10);
  EXPECT_EQ(sg_shading_order(sg_basis(16)), 10);
  for (int lobes : {4, 9, 12}) {
    const SgBasis b = sg_basis(lobes);
    const std::vector<double> g = sg_zonal(b.sharpness, 64);
    double total = 0, below = 0;
    for (int l = 0; l < 64; ++l) total += (2 * l + 1) * g[size_t(l)] * g[size_t(l)];
    const int L = sg_shading_order(b);
    for (int l = 0; l < L; ++l) below += (2 * l + 1) * g[size_t(l)] * g[size_t(l)];
    EXPECT_LE(total - below, 1e-6 * total) << lobes;
    below -= (2 * L - 1) * g[size_t(L - 1)] * g[size_t(L - 1)];
    EXPECT_GT(total - below, 1e-6 * total) << lobes;  // one band fewer would not do
  }
}

TEST(SgAsset, BadBasisLinesAreRefusedNamingTheFile) {
  test::TempDir dir;
  const BakeResult r = bake(sphere_on_plane(), lobe_options(12, 16));
  const std::string path = dir.path("a.ply");
  write_asset(path, r.mesh, r.transfer, r.metadata);
  const std::string good = read_file_bytes(path);
  auto refused = [&](const std::string& bytes, const std::string& words) {
    try {
      parse_asset(bytes, "bad.ply");
      ADD_FAILURE() << "accepted: " << words;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find("bad.ply: "), 0u) << what;
      EXPECT_NE(what.find(words), std::string::npos) << what;
    }
  };
  refused(replaced(good, "sg_lobes 12", "sg_lobes 9"), "9 spherical-Gaussian lobes, but vertices hold 12");
  refused(replaced(good, "sg_lobes 12", "sg_lobes 99"), "is not a lobe count of 4 to 16");
  refused(replaced(good, "sg_lobes 12", "sg_lobes twelve"), "is not a lobe count");
  refused(replaced(good, "sg_sharpness 5.41", "sg_sharpness 6.41"), "is not the sharpness of prtsub's 12 lobes");
  refused(replaced(good, "comment sg_sharpness", "comment sg_sharp"), "without an 'sg_sharpness' line");
  // A writer refuses values that do not match the lobe count before writing anything.
  const std::string none = dir.path("none.ply");
  EXPECT_THROW(write_asset(none, r.mesh, RowMatrixXd(r.transfer.leftCols(9)), r.metadata), InputError);
  EXPECT_FALSE(std::filesystem::exists(none));
}

TEST(SgAsset, GltfCarriesTheLobesAndTurnsThemWithAZUpSource) {
  // glTF: the lobes as _PRT_k, the basis in extras. A z-up source turns to +Y up; the lobes'
  // coefficients stay and their axes turn (extras.sg_axes), so reading it back gives the lobes of
  // the source's own axes again.
  test::TempDir dir;
  const BakeResult r = bake(sphere_on_plane(), lobe_options(9, 32));
  for (UpAxis up : {UpAxis::Y, UpAxis::Z}) {
    GltfOptions g;
    g.up = up;
    const std::string path = dir.path(up == UpAxis::Y ? "y.glb" : "z.glb");
    write_gltf_asset(path, r.mesh, r.transfer, r.metadata, AssetSignal::Transfer, g);
    const Asset a = read_asset(path);
    ASSERT_EQ(a.sg.cols(), 9);
    EXPECT_LT((a.sg - r.transfer).cwiseAbs().maxCoeff(), 1e-6 * r.transfer.cwiseAbs().maxCoeff());
    const Asset ply = make_asset(r.mesh, r.transfer, r.metadata);
    EXPECT_LT((a.transfer - ply.transfer).cwiseAbs().maxCoeff(), 1e-5 * ply.transfer.cwiseAbs().maxCoeff());
    EXPECT_LT((a.positions - ply.positions).cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(SgBake, AdaptiveRefinementSplitsAtTheContactShadowAndKeepsTheLobes) {
  // Refinement keys on the lobes' L² distance (whitened by their Gram matrix): it reaches the
  // budget, the input's vertices keep the values an unrefined bake gives them (the whitening's
  // round trip), every value stays non-negative, and the splits gather where the sphere's shadow
  // falls on the plane rather than on the open plane around it. The same for any thread count.
  const Mesh m = sphere_on_plane();
  BakeOptions o = lobe_options(12, 64);
  const BakeResult flat = bake(m, o);
  o.refine = Refinement::Adaptive;
  o.adaptive.budget = 3 * m.num_faces();
  o.transfer.threads = 1;
  const BakeResult r = bake(m, o);
  EXPECT_EQ(r.mesh.num_faces(), o.adaptive.budget);
  EXPECT_GE(r.transfer.minCoeff(), 0.0);
  EXPECT_LT((r.transfer.topRows(flat.transfer.rows()) - flat.transfer).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(r.metadata.front().first, "prtsub_asset");
  o.transfer.threads = 2;
  EXPECT_EQ(bake(m, o).transfer, r.transfer);
  // Plane faces (z = -1.05) near the contact point against those far out, by count per area.
  const RowMatrixX3d p = vertex_positions(r.mesh);
  double near_area = 0, far_area = 0;
  size_t near_faces = 0, far_faces = 0;
  for (const Triangle& t : r.mesh.triangles) {
    const Eigen::Vector3d a = p.row(t[0]).transpose(), b = p.row(t[1]).transpose(), c = p.row(t[2]).transpose();
    const Eigen::Vector3d centre = (a + b + c) / 3;
    if (std::abs(centre.z() + 1.05) > 1e-9) continue;
    const double area = 0.5 * (b - a).cross(c - a).norm(), radius = centre.head<2>().norm();
    if (radius < 1.2) near_area += area, ++near_faces;
    if (radius > 2.0) far_area += area, ++far_faces;
  }
  ASSERT_GT(near_faces, 0u);
  ASSERT_GT(far_faces, 0u);
  EXPECT_GT(double(near_faces) / near_area, 3 * double(far_faces) / far_area);
}

TEST(SgBake, WhatOnlyShHasIsRefusedWithTheReason) {
  auto refused = [](BakeOptions o, const std::string& words) {
    try {
      check_bake_options(o);
      ADD_FAILURE() << "accepted: " << words;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  refused(lobe_options(3), "4 to 16 lobes, got 3");
  refused(lobe_options(17), "4 to 16 lobes, got 17");
  BakeOptions o = lobe_options(12);
  o.fit.method = FitMethod::LeastSquares;
  refused(o, "--fit point");
  o = lobe_options(12), o.bounce.bounces = 2;
  refused(o, "interreflection");
  o = lobe_options(12), o.target_error = 2;
  refused(o, "--error");
  o = lobe_options(12), o.order_auto = true;
  refused(o, "--order auto");
  o = lobe_options(12), o.round_rays = 32;
  refused(o, "early stop");
  o = lobe_options(12), o.signal = AssetSignal::Ao;
  refused(o, "ambient occlusion");
  o = lobe_options(12), o.refine = Refinement::Auto, o.adaptive.budget = 10;
  refused(o, "--refine auto");
  o = lobe_options(12), o.refine_only = true;
  refused(o, "--stage refine");
  // A budget below the input's would simplify: refused when the input's count is known.
  o = lobe_options(12, 16), o.refine = Refinement::Adaptive, o.adaptive.budget = 10;
  EXPECT_THROW(bake(sphere_on_plane(), o), InputError);
}

TEST(SgCli, BasisIsParsedReportedAndRecorded) {
  test::TempDir dir;
  const std::string in = dir.path("scene.obj"), out = dir.path("a.ply"), rep = dir.path("r.json");
  test::write_obj(in, test::merge(test::icosphere(1), test::quad(3.0, -1.05, true)));
  ASSERT_EQ(test::run_prtsub({"bake", in, "-o", out, "--rays", "16", "--basis", "sg:9", "--report", rep}), 0);
  const std::string report = read_file_bytes(rep);
  EXPECT_NE(report.find("\"basis\": \"sg:9\""), std::string::npos);
  EXPECT_NE(report.find("\"sg_encoding\": \"non-negative\""), std::string::npos);
  EXPECT_EQ(read_asset(out).sg.cols(), 9);
  ASSERT_EQ(test::run_prtsub({"inspect", out, "--report", rep}), 0);
  EXPECT_EQ(test::json_number(read_file_bytes(rep), "lobes"), 9);
  ASSERT_EQ(test::run_prtsub({"bake", in, "-o", out, "--rays", "16", "--basis", "sg:12", "--sg-signed"}), 0);
  bool signed_recorded = false;
  for (const auto& [k, v] : read_asset(out).metadata) signed_recorded |= k == "transfer" && v.find(" signed ") != std::string::npos;
  EXPECT_TRUE(signed_recorded);
  // Bad values: one line, exit 2, nothing written.
  const std::string none = dir.path("none.ply");
  for (const std::vector<std::string>& bad : std::vector<std::vector<std::string>>{{"--basis", "sg:3"},
                                                                                    {"--basis", "sg"},
                                                                                    {"--basis", "sh4"},
                                                                                    {"--basis", "sg:12", "--fit", "lsq"},
                                                                                    {"--basis", "sg:12", "--bounces", "1"},
                                                                                    {"--sg-signed"}}) {
    std::vector<std::string> args = {"bake", in, "-o", none, "--rays", "16"};
    args.insert(args.end(), bad.begin(), bad.end());
    EXPECT_EQ(test::run_prtsub(args), 2) << bad.front();
    EXPECT_FALSE(std::filesystem::exists(none));
  }
}

}  // namespace
}  // namespace prtsub
