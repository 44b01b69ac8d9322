// Relights a prtsub asset under a sun circling the scene and writes one PNG per frame.
//
//   prtsub_relight_example ASSET.ply OUT_PREFIX [FRAMES]
//
// writes OUT_PREFIX0000.png, OUT_PREFIX0001.png, ... What a real-time renderer does each frame
// is the same: rotate the light's SH coefficients (a small matrix product), then take one dot
// product per vertex and let the GPU interpolate.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "prtsub/prt/asset.h"
#include "prtsub/prt/image_io.h"
#include "prtsub/prt/lights.h"
#include "prtsub/prt/render.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s ASSET.ply OUT_PREFIX [FRAMES]\n", argv[0]);
    return 2;
  }
  const int frames = argc > 3 ? std::atoi(argv[3]) : 24;
  try {
    // The asset: render vertices with positions, normals and transfer (docs/asset_format.md).
    prtsub::Asset asset = prtsub::read_asset(argv[1]);

    // The light, projected once at the asset's SH order: a soft sky plus a sun 40° up.
    prtsub::ShLight base = prtsub::default_sky(asset.order);
    base += prtsub::sun_light(asset.order, Eigen::Vector3d(1, 0.84, 0), 2.0);

    // A camera and the primary-ray hits stay fixed; only the light moves.
    const int width = 480, height = 360;
    prtsub::RayScene scene(asset.positions, asset.triangles);
    prtsub::Camera camera = prtsub::auto_camera(prtsub::bounds(asset.positions), width, height);
    prtsub::SurfaceHits hits = prtsub::trace_primary(scene, camera, width, height);

    for (int f = 0; f < frames; ++f) {
      // Rotating the light about +y is a block-diagonal matrix on the coefficients.
      const double angle = 2 * M_PI * f / frames;
      prtsub::ShLight light = prtsub::rotate_light(base, Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix());
      // Per vertex: radiance = albedo/π · Σ l_i t_i. Then interpolate across triangles.
      prtsub::RowMatrixX3d radiance = prtsub::vertex_radiance(asset.transfer, light, 0.8);
      prtsub::Image frame = prtsub::shade_gouraud(hits, asset.triangles, radiance);
      char name[32];
      std::snprintf(name, sizeof name, "%04d.png", f);
      prtsub::write_image(argv[2] + std::string(name), frame);
    }
    std::printf("wrote %d frames to %s0000.png ...\n", frames, argv[2]);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", argv[0], e.what());
    return 1;
  }
}
