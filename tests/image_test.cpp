// Image files through OpenImageIO (prtsub::image), and environment maps read from disk.
#include "prtsub/prt/image_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "cli/specs.h"
#include "helpers.h"
#include "latlong.h"
#include "prtsub/prt/render.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

TEST(Image, EnvSpecReadsAnExrFromDisk) {
  test::TempDir dir;
  Image img = test::latlong(32, 16, [](const Eigen::Vector3d& w) { return Eigen::Vector3d(1 + w.y(), 0.5, 2 + w.x()); });
  write_image(dir.path("env.exr"), img);
  ShLight from_file = parse_light("env:" + dir.path("env.exr"), 3);
  ShLight direct = environment_light(3, img);
  EXPECT_LT((from_file.coeffs - direct.coeffs).cwiseAbs().maxCoeff(), 1e-12);  // EXR float is lossless
  // The +y gradient in band 1. The test map holds each texel's centre value, which misses the
  // texel's mean by about (π/H)²/24 relative (midpoint rule): allow twice that.
  const double expect = std::sqrt(4 * M_PI / 3), h = M_PI / 16;
  EXPECT_NEAR(from_file.coeffs(1, 0), expect, 2 * expect * h * h / 24);
}

TEST(Image, ImagesRoundTripWithTheDocumentedEncoding) {
  test::TempDir dir;
  Image img;
  img.width = 3, img.height = 2, img.channels = 4;
  img.pixels = {0.5f, 0.25f, 2.0f, 1, 0, 0, 0, 0, 1e-3f, 0.9f, 0.1f, 1, 0.5f, 0.5f, 0.5f, 1, 7, 8, 9, 1, 0, 0, 0, 1};
  write_image(dir.path("a.exr"), img);
  Image back = read_image(dir.path("a.exr"));
  EXPECT_EQ(back.pixels, img.pixels);
  write_image(dir.path("a.png"), img, ImageWriteOptions{1.0});
  Image png = read_image(dir.path("a.png"));  // decoded back to linear
  EXPECT_NEAR(linear_to_srgb(0.5), 1.055 * std::pow(0.5, 1 / 2.4) - 0.055, 1e-15);
  EXPECT_NEAR(png.pixels[0], 0.5, 0.004);  // 8-bit quantisation of the sRGB value
  EXPECT_NEAR(png.pixels[2], 1.0, 1e-6);   // clamped
  EXPECT_EQ(png.pixels[7], 0.f);           // alpha 0 stays 0
  EXPECT_THROW(write_image(dir.path("a.bmpx"), img), InputError);
  EXPECT_THROW(write_image(dir.path("no/dir/a.exr"), img), IoError);
  EXPECT_THROW(read_image(dir.path("missing.exr")), IoError);
}

}  // namespace
}  // namespace prtsub
