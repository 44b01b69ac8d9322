// render: an asset relit into a frame, Gouraud (what a GPU shows) or the per-pixel reference.
#include <cstdio>

#include "cli/commands.h"
#include "cli/images.h"
#include "cli/options.h"
#include "cli/report.h"
#include "cli/specs.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/render.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

struct RenderCli {
  std::string input, output, report, size = "800,600", camera = "auto";
  std::vector<std::string> lights, rotations;
  double albedo = -1, exposure = 1.0;  // albedo < 0: the asset's (its per-vertex albedo, or 0.8)
  bool reference = false, compare_bare = false;
  int reference_order = 0;  // 0: the asset's
  int light_order = 0;      // Gouraud: 0, the asset's
  TransferOptions transfer;  // the reference's rays, seed and threads; the order is the asset's
};

// The per-pixel reference frame, and optionally the bare loop's rate over the same rays.
Image reference_frame(const RayScene& scene, const SurfaceHits& hits, const Asset& asset, const ShLight& light,
                      const RenderCli& c, const std::shared_ptr<const AlbedoField>& colour, Report& r) {
  TransferOptions topt = c.transfer;
  topt.order = c.reference_order > 0 ? c.reference_order : asset.order;
  TransferStats stats;
  // A bounced asset's reference bounces as the bake did, at the albedo the asset records.
  const AssetBounces b = asset_bounces(asset, c.input);
  PathOptions bounced;
  bounced.bounces = b.bounces, bounced.albedo = b.albedo, bounced.paths = topt.rays, bounced.seed = topt.seed + 1;
  bounced.threads = topt.threads;
  if (b.bounces > 0 && !colour && std::abs(b.albedo - c.albedo) > 1e-9)
    std::fprintf(stderr, "prtsub render: warning: %s was baked with bounces at albedo %g; shading at --albedo %g\n", c.input.c_str(),
                 b.albedo, c.albedo);
  Progress progress("reference", hits.covered() * (b.bounces > 0 ? 2 : 1), stderr_is_terminal());
  Image frame = render_reference(scene, hits, asset.positions, asset.normals, asset.triangles, light, c.albedo, topt, &stats,
                                 [&](size_t n) { progress.add(n); }, b.bounces > 0 ? &bounced : nullptr, colour);
  progress.finish();
  if (b.bounces > 0) {
    r.set("reference_bounces", b.bounces);
    if (b.coloured) r.set("reference_albedo", albedo_description(b.spec));
    else r.set("reference_albedo", b.albedo);
  }
  r.set("rays", stats.rays);
  r.set("rays_per_pixel", topt.rays);
  r.set("reference_rays_per_second", static_cast<double>(stats.rays) / std::max(stats.seconds, 1e-9));
  r.set("reference_mrays", static_cast<double>(stats.rays) / std::max(stats.seconds, 1e-9) / 1e6);
  if (c.compare_bare) {
    RowMatrixX3d points, point_normals;
    hit_points(hits, asset.positions, asset.normals, asset.triangles, points, point_normals);
    TransferStats bare;
    bare_occlusion_loop(scene, points, point_normals, topt, &bare);
    r.set("bare_rays_per_second", static_cast<double>(bare.rays) / std::max(bare.seconds, 1e-9));
    r.set("bare_mrays", static_cast<double>(bare.rays) / std::max(bare.seconds, 1e-9) / 1e6);
  }
  return frame;
}

double mean_covered_radiance(const Image& frame, const SurfaceHits& hits) {
  double sum = 0;
  for (size_t i = 0; i < hits.face.size(); ++i)
    if (hits.face[i] >= 0) sum += (frame.pixels[4 * i] + frame.pixels[4 * i + 1] + frame.pixels[4 * i + 2]) / 3.0;
  return hits.covered() ? sum / static_cast<double>(hits.covered()) : 0.0;
}

}  // namespace

int cmd_render(int argc, char** argv) {
  RenderCli c;
  ArgParser args("render",
                 "Renders an asset under SH light: Gouraud-interpolated per-vertex PRT (what a GPU shows), or with\n"
                 "--reference the per-pixel ground truth (transfer computed at every pixel's hit point).");
  args.positional("ASSET", "an asset written by prtsub bake (.ply, .glb or .gltf)", &c.input);
  args.option("--light", "SPEC", "env:PATH | sh:c0,c1,... | sun:X,Y,Z[,RADIUS_DEG] | sky[:UPX,UPY,UPZ] | random:SEED | const:R,G,B; lights add up", &c.lights);
  args.option("--light-rotate", "AXIS,DEG", "rotate the light about x, y, z or X,Y,Z", &c.rotations);
  args.option("--output", "FRAME.png|FRAME.exr", "output frame (required); EXR is linear float RGBA", &c.output);
  args.alias("-o", "--output");
  args.option("--size", "W,H", "frame size in pixels [default 800,600]", &c.size);
  args.option("--camera", "auto|eye=X,Y,Z:target=X,Y,Z:up=X,Y,Z:fov=DEG", "camera [default auto]", &c.camera);
  args.option("--albedo", "A", "diffuse albedo, grey [default the asset's: the albedo it stores per vertex, else 0.8]", &c.albedo, 0.0, 1.0);
  args.option("--exposure", "E", "PNG only: linear radiance is multiplied by E before the sRGB curve", &c.exposure, 0.0, 1e6);
  args.flag("--reference", "render the per-pixel reference instead of the Gouraud frame", &c.reference);
  args.option("--reference-order", "N", "the reference's SH order (and the light's), to see what the asset's order leaves out\n"
              "[default the asset's]", &c.reference_order, 0, kMaxShOrder);
  args.option("--light-order", "N", "Gouraud: the light's SH order, the asset seeing the bands it has, so that assets of\n"
              "different orders see one light (random lights differ by order) [default the asset's]", &c.light_order, 0, kMaxShOrder);
  add_transfer_options(args, c.transfer, false);
  args.flag("--compare-bare", "reference: also time a bare Embree loop over the same rays (report: bare_rays_per_second)", &c.compare_bare);
  add_report_option(args, c.report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (c.output.empty()) throw UsageError("render: missing -o FRAME.png|FRAME.exr");
  if (c.lights.empty()) throw UsageError("render: missing --light SPEC");
  int width = 0, height = 0;
  parse_size(c.size, "--size", width, height);
  const Camera given_camera = c.camera == "auto" ? Camera{} : parse_camera(c.camera);
  std::vector<Eigen::Matrix3d> rotations;
  for (const std::string& spec : c.rotations) rotations.push_back(parse_rotation(spec));
  check_writable(c.output);
  if (!c.report.empty()) check_writable(c.report);

  Stopwatch clock;
  Report r;
  const Asset asset = read_asset(c.input);
  r.set("seconds_load", clock.lap());
  if (c.reference_order > 0 && !c.reference) throw UsageError("render: --reference-order needs --reference");
  if (c.light_order > 0 && c.reference) throw UsageError("render: --light-order is for Gouraud frames; the reference's is --reference-order");
  ShLight light = parse_lights(c.lights, c.reference_order > 0 ? c.reference_order : c.light_order > 0 ? c.light_order : asset.order);
  for (const Eigen::Matrix3d& rotation : rotations) light = rotate_light(light, rotation);
  const Camera camera = c.camera == "auto" ? auto_camera(bounds(asset.positions), width, height) : given_camera;
  r.set("seconds_light", clock.lap());
  const RayScene scene(asset.positions, asset.triangles);
  r.set("seconds_scene", clock.lap());
  const SurfaceHits hits = trace_primary(scene, camera, width, height, c.transfer.threads);
  const double t_primary = clock.lap();
  // A coloured asset shades with the albedo it stores (and its bounces carry it).
  const std::shared_ptr<const AlbedoField> colour = cli_asset_albedo(asset, c.input);
  if (colour && c.albedo >= 0) throw UsageError("render: " + c.input + " stores its own albedo per vertex; --albedo is for grey assets");
  if (c.albedo < 0) c.albedo = 0.8;
  const Image frame = c.reference ? reference_frame(scene, hits, asset, light, c, colour, r)
                                  : shade_gouraud(hits, asset.triangles, colour ? vertex_radiance(asset.transfer, light, asset.albedo)
                                                                                : vertex_radiance(asset.transfer, light, c.albedo));
  const double t_shade = clock.lap();
  cli_write_image(c.output, frame, ImageWriteOptions{c.exposure});
  r.set("seconds_write", clock.lap());

  r.set("command", "render");
  r.set("input", c.input);
  r.set("output", c.output);
  r.set("mode", c.reference ? "reference" : "gouraud");
  r.set("mode_text", c.reference ? "per-pixel reference" : "Gouraud");
  r.set("width", width);
  r.set("height", height);
  r.set("triangles", asset.triangles.size());
  r.set("pixels_covered", hits.covered());
  r.set("covered_fraction", static_cast<double>(hits.covered()) / (static_cast<double>(width) * height));
  r.set("mean_radiance", mean_covered_radiance(frame, hits));
  char camera_text[256];
  std::snprintf(camera_text, sizeof camera_text, "eye %g,%g,%g target %g,%g,%g up %g,%g,%g fov %g", camera.eye.x(), camera.eye.y(),
                camera.eye.z(), camera.target.x(), camera.target.y(), camera.target.z(), camera.up.x(), camera.up.y(), camera.up.z(),
                camera.fov_deg);
  r.set("camera", camera_text);
  r.set("seconds_primary", t_primary);
  r.set("seconds_shade", t_shade);
  r.set("seconds_frame", t_primary + t_shade);
  r.set("seconds_total", clock.total());
  r.set("peak_memory_mib", peak_memory_mib());
  r.print(stdout, {"prtsub render: {input} -> {output} ({mode_text})",
                   "  frame:      {width}x{height}, {pixels_covered} pixels covered ({covered_fraction:%1}), mean radiance {mean_radiance}",
                   "  camera:     {camera}", "  reference:  {rays} rays, {reference_mrays:2} Mrays/s",
                   "              {reference_bounces} bounces at albedo {reference_albedo}, traced as paths through the surface",
                   "              bare loop {bare_mrays:2} Mrays/s",
                   "  time:       {seconds_total:3} s total (load {seconds_load:3}, light {seconds_light:3}, scene "
                   "{seconds_scene:3}, primary {seconds_primary:3}, shade {seconds_shade:3}, write {seconds_write:3})"});
  if (!c.report.empty()) r.write(c.report);
  return 0;
}

}  // namespace prtsub
