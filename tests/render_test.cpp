#include "prtsub/prt/render.h"

#include <gtest/gtest.h>

#include "helpers.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

// A baked scene held the way an asset holds it: per-render-vertex positions.
struct Baked {
  Mesh mesh;
  RowMatrixX3d positions;
  RowMatrixXd transfer;
  std::unique_ptr<RayScene> scene;
  Baked(const RawMesh& raw, int order, int rays) : mesh(test::build(raw)) {
    positions.resize(static_cast<Eigen::Index>(mesh.num_vertices()), 3);
    for (uint32_t v = 0; v < mesh.num_vertices(); ++v) positions.row(v) = mesh.point(v).transpose();
    scene = std::make_unique<RayScene>(positions, mesh.triangles);
    TransferOptions o;
    o.order = order, o.rays = rays;
    transfer = shadowed_transfer(*scene, positions, mesh.normals, o);
  }
};

TEST(Render, PrimaryRaysGoThroughPixelCentres) {
  Camera cam;
  cam.eye = Eigen::Vector3d(0, 0, 0), cam.target = Eigen::Vector3d(0, 0, -1), cam.up = Eigen::Vector3d(0, 1, 0), cam.fov_deg = 90;
  // W=4, H=2, tan(45°)=1: column 3 -> x = (2·3.5/4 − 1)·2 = 1.5; row 0 -> y = 1 − 0.5 = 0.5.
  Eigen::Vector3d d = camera_ray(cam, 3, 0, 4, 2);
  EXPECT_LT((d - Eigen::Vector3d(1.5, 0.5, -1).normalized()).norm(), 1e-12);
  EXPECT_LT((camera_ray(cam, 0, 0, 1, 1) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  Camera same = cam;
  same.target = same.eye;
  EXPECT_THROW(check_camera(same), InputError);
  Camera along = cam;
  along.up = Eigen::Vector3d(0, 0, 2);
  EXPECT_THROW(check_camera(along), InputError);
  const Mesh cube = test::build(test::cube());
  const RayScene scene(cube.positions, position_triangles(cube));
  EXPECT_THROW(trace_primary(scene, same, 4, 4), InputError);
}

TEST(Render, UnoccludedSphereUnderLinearLightMatchesClosedForm) {
  // L(ω) = a + b ω_z gives B = albedo (a + 2/3 b n_z) at an unshadowed point with normal n.
  const double a = 0.6, b = 0.3, albedo = 0.8;
  const int order = 3;
  ShLight light = coefficients_light(order, {a * 2 * std::sqrt(M_PI), 0, b * std::sqrt(4 * M_PI / 3)});
  Baked s(test::icosphere(5), order, 16);
  Camera cam;
  cam.eye = Eigen::Vector3d(3, 1, 2), cam.target = Eigen::Vector3d::Zero(), cam.fov_deg = 45;
  SurfaceHits hits = trace_primary(*s.scene, cam, 96, 96);
  ASSERT_GT(hits.covered(), 2000u);
  RowMatrixX3d points, normals;
  hit_points(hits, s.positions, s.mesh.normals, s.mesh.triangles, points, normals);

  // The per-pixel reference at 1024 rays: within 1e-3 relative of the closed form.
  TransferOptions o;
  o.order = order, o.rays = 1024;
  Image ref = render_reference(*s.scene, hits, s.positions, s.mesh.normals, s.mesh.triangles, light, albedo, o);
  // Gouraud: per-vertex radiance interpolated; equals the closed form at the interpolated,
  // unnormalised normal exactly, and at the normalised one within the tessellation's error.
  Image gouraud = shade_gouraud(hits, s.mesh.triangles, vertex_radiance(s.transfer, light, albedo));
  Eigen::Index k = 0;
  double worst_ref = 0, worst_interp = 0, worst_tess = 0;
  for (size_t i = 0; i < hits.face.size(); ++i) {
    if (hits.face[i] < 0) {
      EXPECT_EQ(ref.pixels[4 * i + 3], 0.f);
      EXPECT_EQ(gouraud.pixels[4 * i + 3], 0.f);
      continue;
    }
    const double expect = albedo * (a + 2.0 / 3.0 * b * normals(k, 2));
    const Triangle& t = s.mesh.triangles[static_cast<size_t>(hits.face[i])];
    const double u = hits.u[i], v = hits.v[i];
    const double nz_lin = (1 - u - v) * s.mesh.normals(t[0], 2) + u * s.mesh.normals(t[1], 2) + v * s.mesh.normals(t[2], 2);
    const double expect_lin = albedo * (a + 2.0 / 3.0 * b * nz_lin);
    for (int c = 0; c < 3; ++c) {
      worst_ref = std::max(worst_ref, std::abs(ref.pixels[4 * i + c] - expect) / expect);
      worst_interp = std::max(worst_interp, std::abs(gouraud.pixels[4 * i + c] - expect_lin) / expect_lin);
      worst_tess = std::max(worst_tess, std::abs(gouraud.pixels[4 * i + c] - expect) / expect);
    }
    ++k;
  }
  EXPECT_LT(worst_ref, 1e-3);
  EXPECT_LT(worst_interp, 1e-5);  // float rounding only
  EXPECT_LT(worst_tess, 2e-3);    // level-5 icosphere: normals interpolate to within 0.1%
}

TEST(Render, SunShadowFallsWhereTheGeometrySays) {
  // A unit sphere resting on the plane z = -1 under a sun of 3° radius, 35° above the horizon,
  // seen from the side away from the sun so the shadow is in view.
  // A plane point is in the umbra when its ray towards the sun passes within the sphere.
  const int order = 10;
  Baked s(test::merge(test::icosphere(3), test::quad(5.0, -1.0, true)), order, 16);
  const Eigen::Vector3d d = Eigen::Vector3d(1, 0, 0.7).normalized();
  ShLight sun = sun_light(order, d, 3.0);
  Camera cam;
  cam.eye = Eigen::Vector3d(-5, -4, 6), cam.target = Eigen::Vector3d(-1.5, 0, -1), cam.fov_deg = 50;
  SurfaceHits hits = trace_primary(*s.scene, cam, 80, 80);
  TransferOptions o;
  o.order = order, o.rays = 512;
  Image ref = render_reference(*s.scene, hits, s.positions, s.mesh.normals, s.mesh.triangles, sun, 1.0, o);
  RowMatrixX3d points, normals;
  hit_points(hits, s.positions, s.mesh.normals, s.mesh.triangles, points, normals);
  // Angular margin of the sun direction inside the cone the sphere subtends from p (positive:
  // the sun's centre is behind the sphere). Order-10 SH resolve about 180°/10 = 18°, so the
  // rendered shadow is soft, but its half-way point must sit on the geometric edge (margin 0).
  std::vector<double> inside, outside, edge;
  Eigen::Index k = 0;
  for (size_t i = 0; i < hits.face.size(); ++i) {
    if (hits.face[i] < 0) continue;
    Eigen::Vector3d p = points.row(k++).transpose();
    if (std::abs(p.z() + 1) > 1e-6 || p.head<2>().norm() > 4) continue;  // plane pixels only
    const double cone = std::asin(1 / p.norm()), angle = std::acos(std::clamp((-p).normalized().dot(d), -1.0, 1.0));
    const double margin = (cone - angle) * 180 / M_PI;
    const double r = ref.pixels[4 * i];
    if (margin > 8) inside.push_back(r);
    if (margin < -15) outside.push_back(r);
    if (std::abs(margin) < 3) edge.push_back(r);
  }
  ASSERT_GT(inside.size(), 30u);
  ASSERT_GT(outside.size(), 100u);
  ASSERT_GT(edge.size(), 30u);
  auto mean = [](const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m += x / static_cast<double>(v.size());
    return m;
  };
  const double lit = mean(outside);
  // Lit ground: radiance ≈ n·d for albedo 1 (the sun delivers irradiance π at normal incidence).
  EXPECT_NEAR(lit, d.z(), 0.1 * d.z());
  for (double v : outside) EXPECT_GT(v, 0.8 * lit);
  for (double v : inside) EXPECT_LT(v, 0.25 * lit);
  EXPECT_LT(mean(inside), 0.1 * lit);
  EXPECT_GT(mean(edge), 0.3 * lit);
  EXPECT_LT(mean(edge), 0.7 * lit);
}

TEST(Render, ImageErrorHasClosedForms) {
  Image b;
  b.width = 4, b.height = 1, b.channels = 4;
  b.pixels = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 9, 9, 9, 0};  // last pixel uncovered
  Image a = b;
  ImageError same = image_error(a, b);
  EXPECT_EQ(same.rmse_relative, 0.0);
  EXPECT_TRUE(std::isinf(same.psnr_db));
  EXPECT_EQ(same.pixels, 3u);
  for (int i = 0; i < 12; ++i) a.pixels[i] = (i % 4 == 3) ? 1.f : 1.1f;
  Image heat;
  ImageError e = image_error(a, b, &heat);
  EXPECT_NEAR(e.rmse_relative, 0.1, 1e-6);
  EXPECT_NEAR(e.psnr_db, 20 * std::log10(1 / 0.1), 1e-4);
  EXPECT_EQ(heat.width, 4);
  Image c = b;
  c.width = 2;
  EXPECT_THROW(image_error(c, b), InputError);
}

// compare's heat maps share one absolute scale: the same error is the same colour in every
// frame judged against one reference, whatever each frame's own RMSE.
TEST(Render, HeatMapsOnOneScaleShowTheSameErrorInTheSameColour) {
  Image b;
  b.width = 3, b.height = 1, b.channels = 3;
  b.pixels = {1, 1, 1, 1, 1, 1, 1, 1, 1};  // mean 1
  Image one = b, two = b;
  for (int c = 0; c < 3; ++c) one.pixels[size_t(c)] = 1.125f, two.pixels[size_t(c)] = 1.125f, two.pixels[size_t(3 + c)] = 1.5f;
  Image h1, h2;
  image_error(one, b, &h1, 0.5);
  image_error(two, b, &h2, 0.5);
  auto srgb = [](float linear) { return linear <= 0.0031308f ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055; };
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(h1.pixels[size_t(c)], h2.pixels[size_t(c)]);           // error 0.125 in both
    EXPECT_NEAR(srgb(h1.pixels[size_t(c)]), kHeatStops[1][c], 1e-5);  // a quarter of the scale
    EXPECT_NEAR(srgb(h2.pixels[size_t(3 + c)]), kHeatStops[4][c], 1e-5);  // 0.5: the scale, yellow
    EXPECT_EQ(h1.pixels[size_t(6 + c)], 0.f);                          // no error: black
  }
  // Scaled each to its own error instead, the same pixel differs.
  image_error(one, b, &h1), image_error(two, b, &h2);
  EXPECT_NE(h1.pixels[0], h2.pixels[0]);
}

}  // namespace
}  // namespace prtsub
