// Coloured albedo against independent computations: each channel of a coloured bounce is the
// grey bounce at that channel's albedo (the passes are linear in the albedo and share their
// rays), a channel of albedo 0 keeps only its direct light, a furnace channel of albedo 1 still
// converges, albedo at a hit is interpolated (or read from a map at the hit's UV), the path
// reference follows the same rule per channel, and RGB assets round-trip through PLY and glTF.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.h"
#include "prtsub/prt/albedo.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/gltf.h"
#include "prtsub/prt/interreflection.h"
#include "prtsub/prt/path_transfer.h"
#include "prtsub/prt/render.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

std::shared_ptr<const AlbedoField> constant_colour(const Mesh& mesh, const Eigen::Vector3d& rgb) {
  AlbedoSpec s;
  s.constant = rgb;
  return std::make_shared<const AlbedoField>(mesh, s);
}

// A plate facing down over a ground: the ground receives the plate's light. With its scene, the
// direct transfer at its vertices (order 3, 64 rays) and three bounces of a coloured albedo.
Mesh plate_over_ground() { return test::build(test::merge(test::quad(2.0, 0.0, true), test::quad(1.0, 0.5, false))); }

struct ColouredPlate {
  Mesh mesh = plate_over_ground();
  RayScene scene{mesh.positions, position_triangles(mesh)};
  RowMatrixXd direct;
  Eigen::Vector3d rho{0.9, 0.5, 0.2};
  BounceOptions b;
  explicit ColouredPlate(int rays) {
    TransferOptions t;
    t.order = 3, t.rays = 64;
    direct = shadowed_transfer(scene, vertex_positions(mesh), mesh.normals, t);
    b.bounces = 3, b.rays = rays;
    b.colour = constant_colour(mesh, rho);
  }
};

TEST(Colour, ABounceNoiseEstimateOfColourIsTheMeanOfItsChannelsGreyEstimates) {
  // The same rays in every channel (the gathers' seeds do not depend on the albedo): the RGB
  // estimate is the mean over channels of the grey ones at each channel's albedo, exactly.
  ColouredPlate p(16);
  const Mesh& mesh = p.mesh;
  const RayScene& scene = p.scene;
  const RowMatrixXd& direct = p.direct;
  BounceOptions& b = p.b;
  uint64_t rays = 0;
  const double rgb = bounce_noise(mesh, scene, direct, b, 100, &rays);
  double mean = 0;
  for (int c = 0; c < 3; ++c) {
    BounceOptions g = b;
    g.colour = nullptr, g.albedo = p.rho[c];
    mean += bounce_noise(mesh, scene, direct, g, 100, &rays) / 3;
  }
  EXPECT_GT(rgb, 0.0);
  EXPECT_NEAR(rgb, mean, 1e-12 * mean);
  b.bounces = 0;
  EXPECT_EQ(bounce_noise(mesh, scene, direct, b, 100, &rays), 0.0);
  EXPECT_THROW(bounce_noise(mesh, scene, direct.topRows(2), b, 100, &rays), InputError);
}

TEST(Colour, EachChannelOfAColouredBounceIsTheGreyBounceAtThatChannelsAlbedo) {
  const ColouredPlate p(64);
  const Mesh& mesh = p.mesh;
  const RayScene& scene = p.scene;
  const RowMatrixXd& direct = p.direct;
  const Eigen::Vector3d& rho = p.rho;
  const BounceOptions& b = p.b;
  RowMatrixXd before_rgb;
  const RowMatrixXd rgb = interreflected_transfer(mesh, scene, direct, b, nullptr, &before_rgb);
  const Eigen::Index K = direct.cols();
  ASSERT_EQ(rgb.cols(), 3 * K);
  ASSERT_EQ(transfer_channels(rgb.cols()), 3);
  double added = 0;
  for (int c = 0; c < 3; ++c) {
    BounceOptions g = b;
    g.colour = nullptr, g.albedo = rho[c];
    RowMatrixXd before;
    const RowMatrixXd grey = interreflected_transfer(mesh, scene, direct, g, nullptr, &before);
    EXPECT_LT((rgb.middleCols(c * K, K) - grey).cwiseAbs().maxCoeff(), 1e-12) << c;
    EXPECT_LT((before_rgb.middleCols(c * K, K) - before).cwiseAbs().maxCoeff(), 1e-12) << c;
    added = std::max(added, (grey - direct).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(added, 0.01) << "the plate must light the ground, or the test shows nothing";
}

TEST(Colour, AChannelOfAlbedoZeroKeepsItsDirectLightAndOneOfAlbedoOneFillsTheFurnace) {
  // The bowl of the white furnace: its red channel at albedo 1 converges to the light's
  // radiance, its blue at albedo 0 never bounces.
  const Mesh mesh = test::build(test::bowl(3));
  const RayScene scene(mesh.positions, position_triangles(mesh));
  TransferOptions t;
  t.order = 2, t.rays = 1024;
  const RowMatrixXd direct = shadowed_transfer(scene, vertex_positions(mesh), mesh.normals, t);
  BounceOptions b;
  b.bounces = 8, b.rays = 1024;
  b.colour = constant_colour(mesh, Eigen::Vector3d(1, 0.5, 0));
  const RowMatrixXd rgb = interreflected_transfer(mesh, scene, direct, b);
  const Eigen::Index K = direct.cols();
  EXPECT_EQ((rgb.middleCols(2 * K, K) - direct).cwiseAbs().maxCoeff(), 0.0);
  const double want = std::sqrt(M_PI) / 2;  // t0 of an open point: radiance 1 under light 1
  double red = 0, green = 0;
  for (Eigen::Index v = 0; v < rgb.rows(); ++v) red += std::abs(rgb(v, 0) - want), green += rgb(v, K) - direct(v, 0);
  red /= static_cast<double>(rgb.rows()), green /= static_cast<double>(rgb.rows());
  EXPECT_LT(red, 0.012);  // as the grey furnace: within the rays' noise after eight bounces
  EXPECT_GT(green, 0.05);  // half the albedo still adds light, less than the red channel's
  double red_added = 0;
  for (Eigen::Index v = 0; v < rgb.rows(); ++v) red_added += rgb(v, 0) - direct(v, 0);
  EXPECT_LT(green, red_added / static_cast<double>(rgb.rows()));
}

TEST(Colour, VertexColoursAreInterpolatedAtAHitAndAMapIsSampledAtItsUv) {
  RawMesh raw = test::quad(1.0, 0.0, true);
  raw.colors.resize(4, 3);
  raw.colors << 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  raw.colors_linear = true;
  raw.texcoords.resize(4, 2);
  raw.texcoords << 0, 0, 1, 0, 1, 1, 0, 1;
  const Mesh mesh = test::build(raw);
  ASSERT_TRUE(mesh.has_colors());
  AlbedoSpec v;
  v.source = AlbedoSource::Vertex;
  const AlbedoField field(mesh, v);
  const Triangle& tri = mesh.triangles[0];
  const Eigen::Vector3d expect = 0.5 * mesh.colors.row(tri[0]) + 0.3 * mesh.colors.row(tri[1]) + 0.2 * mesh.colors.row(tri[2]);
  EXPECT_LT((field.at(0, 0.3, 0.2) - expect).norm(), 1e-15);
  // A 2 by 1 map, red on the left, green on the right: bilinear between pixel centres, repeating.
  auto image = std::make_shared<Image>();
  image->width = 2, image->height = 1, image->channels = 3;
  image->pixels = {1, 0, 0, 0, 1, 0};
  EXPECT_LT((sample_albedo_map(*image, 0.25, 0.5) - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((sample_albedo_map(*image, 0.5, 0.5) - Eigen::Vector3d(0.5, 0.5, 0)).norm(), 1e-12);
  EXPECT_LT((sample_albedo_map(*image, 1.0, 0.5) - Eigen::Vector3d(0.5, 0.5, 0)).norm(), 1e-12);  // wraps
  AlbedoSpec m;
  m.source = AlbedoSource::Map, m.map = "two.png", m.image = image;
  const AlbedoField mapped(mesh, m);
  const Eigen::RowVector2d uv = 0.5 * mesh.uv.row(tri[0]) + 0.3 * mesh.uv.row(tri[1]) + 0.2 * mesh.uv.row(tri[2]);
  EXPECT_LT((mapped.at(0, 0.3, 0.2) - sample_albedo_map(*image, uv.x(), uv.y())).norm(), 1e-12);
  // What each source needs.
  EXPECT_THROW(AlbedoField(test::build(test::quad(1.0, 0.0, true)), v), InputError);
  m.image = nullptr;
  EXPECT_THROW(AlbedoField(mesh, m), InputError);
  image->pixels[0] = 2;  // an albedo above 1
  m.image = image;
  EXPECT_THROW(AlbedoField(mesh, m), InputError);
}

TEST(Colour, AlbedoSpecsParseAndSayWhatTheyAre) {
  EXPECT_FALSE(parse_albedo("0.8").coloured());
  EXPECT_TRUE(parse_albedo("0.8,0.5,0.2").coloured());
  EXPECT_FALSE(parse_albedo("0.5,0.5,0.5").coloured());
  EXPECT_EQ(parse_albedo("vertex").source, AlbedoSource::Vertex);
  EXPECT_EQ(albedo_description(parse_albedo("0.8,0.5,0.2")), "0.8,0.5,0.2");
  for (const char* bad : {"", "1.5", "0.8,0.5", "red", "0.8,0.5,-0.1", "nan"}) EXPECT_THROW(parse_albedo(bad), InputError) << bad;
}

TEST(Colour, ThePathReferenceCarriesEachChannelsAlbedoAsTheGreyOneDoes) {
  // The paths' directions do not depend on the albedo, so a coloured reference is, channel by
  // channel, the grey reference at that channel's albedo (and the plain estimator too).
  const Mesh mesh = plate_over_ground();
  const RayScene scene(mesh.positions, position_triangles(mesh));
  const RowMatrixX3d corners = vertex_positions(mesh);
  const PathSurface surface{corners, mesh.normals, mesh.triangles};
  RowMatrixX3d points(3, 3), normals(3, 3);
  points << 0.2, 0.1, 0.0, -0.5, 0.3, 0.0, 1.5, 1.5, 0.0;
  normals << 0, 0, 1, 0, 0, 1, 0, 0, 1;
  const Eigen::Vector3d rho(0.9, 0.4, 0.0);
  for (const bool plain : {false, true}) {
    PathOptions o;
    o.order = 2, o.paths = 256, o.bounces = 2, o.plain = plain;
    o.colour = constant_colour(mesh, rho);
    const RowMatrixXd rgb = path_traced_transfer(scene, surface, points, normals, o);
    ASSERT_EQ(rgb.cols(), 12);
    for (int c = 0; c < 3; ++c) {
      PathOptions g = o;
      g.colour = nullptr, g.albedo = rho[c];
      const RowMatrixXd grey = path_traced_transfer(scene, surface, points, normals, g);
      EXPECT_LT((rgb.middleCols(4 * c, 4) - grey).cwiseAbs().maxCoeff(), 1e-12) << plain << " " << c;
    }
    if (!plain) {
      EXPECT_EQ(rgb.rightCols(4).cwiseAbs().maxCoeff(), 0.0);  // albedo 0: no bounced light
    }
  }
}

TEST(Colour, RgbAssetsRoundTripThroughPlyAndGltfAndShadeEachChannelWithItsOwnBlock) {
  const Mesh mesh = plate_over_ground();
  const Eigen::Index V = static_cast<Eigen::Index>(mesh.num_vertices());
  RowMatrixXd t = RowMatrixXd::Random(V, 27);  // order 3, three channels
  RowMatrixX3d albedo = (RowMatrixX3d::Random(V, 3).array() * 0.5 + 0.5).matrix();
  Metadata meta = sh_convention_metadata(3);
  test::TempDir dir;
  for (const char* name : {"rgb.ply", "rgb.glb", "rgb.gltf"}) {
    const std::string path = dir.path(name);
    const bool gltf = is_gltf_path(path);
    if (gltf) write_gltf_asset(path, mesh, t, meta, AssetSignal::Transfer, {}, albedo);
    else write_asset(path, mesh, t, meta, AssetSignal::Transfer, albedo);
    const Asset a = read_asset(path);
    EXPECT_EQ(a.channels, 3) << name;
    EXPECT_EQ(a.order, 3) << name;
    EXPECT_LT((a.transfer - t).cwiseAbs().maxCoeff(), 1e-6) << name;
    EXPECT_LT((a.albedo - albedo).cwiseAbs().maxCoeff(), 1e-6) << name;
  }
  // glTF in Z-up: the SH of every channel turns with the axes, and back on reading.
  GltfOptions z;
  z.up = UpAxis::Z;
  write_gltf_asset(dir.path("z.glb"), mesh, t, meta, AssetSignal::Transfer, z, albedo);
  EXPECT_LT((read_asset(dir.path("z.glb")).transfer - t).cwiseAbs().maxCoeff(), 1e-5);
  // Shading: channel c of the radiance is albedo_c/π times light channel c against block c.
  const ShLight light = random_light(3, 7);
  const RowMatrixX3d radiance = vertex_radiance(t, light, albedo);
  for (int c = 0; c < 3; ++c) {
    const Eigen::VectorXd want = (t.middleCols(9 * c, 9) * light.coeffs.col(c)).cwiseProduct(albedo.col(c)) / M_PI;
    EXPECT_LT((radiance.col(c) - want).cwiseAbs().maxCoeff(), 1e-12) << c;
  }
  // Shapes that are neither N² nor 3·N², and albedos outside [0, 1], are refused.
  EXPECT_THROW(write_asset(dir.path("bad.ply"), mesh, RowMatrixXd::Zero(V, 10), meta), InputError);
  albedo(0, 0) = 1.5;
  EXPECT_THROW(write_asset(dir.path("bad.ply"), mesh, t, meta, AssetSignal::Transfer, albedo), InputError);
  EXPECT_FALSE(test::file_exists(dir.path("bad.ply")));
}

TEST(Colour, EvalJudgesRgbAgainstRgbAndRefusesToMixThem) {
  const Mesh mesh = plate_over_ground();
  const RayScene scene(mesh.positions, position_triangles(mesh));
  ReferenceOptions ro;
  ro.points = 200, ro.rays = 64, ro.order = 2, ro.noise_points = 50, ro.bounces = 1;
  ro.colour = constant_colour(mesh, Eigen::Vector3d(0.8, 0.8, 0.8));
  const Reference rgb = make_reference(mesh, scene, ro);
  ASSERT_EQ(rgb.transfer.cols(), 12);
  ReferenceOptions grey_options = ro;
  grey_options.colour = nullptr, grey_options.albedo = 0.8;
  const Reference grey = make_reference(mesh, scene, grey_options);
  // A grey albedo given as colour: every channel is the grey reference, and so is its noise.
  for (int c = 0; c < 3; ++c) EXPECT_LT((rgb.transfer.middleCols(4 * c, 4) - grey.transfer).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(rgb.noise_floor, grey.noise_floor, 1e-12);
  // An asset that is the grey reference's values per channel scores what the grey one scores.
  RowMatrixXd asset = RowMatrixXd::Zero(static_cast<Eigen::Index>(mesh.num_vertices()), 4);
  const EvalResult e_grey = evaluate(grey, vertex_positions(mesh), mesh.triangles, mesh.source_face, asset);
  const EvalResult e_rgb = evaluate(rgb, vertex_positions(mesh), mesh.triangles, mesh.source_face, asset.replicate(1, 3));
  EXPECT_NEAR(e_rgb.rms_percent, e_grey.rms_percent, 1e-9);
  EXPECT_GT(e_grey.rms_percent, 50.0);
  EXPECT_THROW(evaluate(rgb, vertex_positions(mesh), mesh.triangles, mesh.source_face, asset), InputError);
}

TEST(Colour, AColouredBakeBouncesVertexColoursAndRecordsThem) {
  // The ground is white; the plate above it is red. Baked with the vertex colours, the ground's
  // red channel receives the plate's light and its green and blue nothing more than direct.
  RawMesh ground = test::quad(2.0, 0.0, true), plate = test::quad(1.0, 0.5, false);
  ground.colors.setOnes(4, 3);
  plate.colors.resize(4, 3);
  plate.colors.rowwise() = Eigen::RowVector3d(1, 0, 0);
  const Mesh mesh = test::build(test::merge(ground, plate));
  BakeOptions o;
  o.transfer.order = 2, o.transfer.rays = 64;
  o.bounce.bounces = 2;
  o.albedo_colour.source = AlbedoSource::Vertex;
  o.fit.method = FitMethod::Point;
  const BakeResult r = bake(mesh, o);
  ASSERT_EQ(r.transfer.cols(), 12);
  ASSERT_EQ(r.albedo.rows(), r.transfer.rows());
  double red = 0, green = 0;
  for (Eigen::Index v = 0; v < r.transfer.rows(); ++v) {
    if (mesh.point(static_cast<uint32_t>(v)).z() != 0.0) continue;  // the ground's corners
    red += r.transfer(v, 0) - r.point(v, 0), green += r.transfer(v, 4) - r.point(v, 0);
  }
  EXPECT_GT(red, 0.01);
  EXPECT_NEAR(green, 0.0, 1e-12) << "green light bounces off the ground only, which sees nothing but the red plate's underside";
  bool said = false;
  for (const auto& [k, v] : r.metadata) said |= k == "albedo" && v.find("vertex") == 0;
  EXPECT_TRUE(said);
  o.albedo_colour.source = AlbedoSource::Vertex;
  EXPECT_THROW(bake(test::build(test::quad(1.0, 0.0, true)), o), InputError);  // no colours to use
}

}  // namespace
}  // namespace prtsub
