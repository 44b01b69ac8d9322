// view: an asset in the relighting viewer, one HTML file that opens from disk (docs/viewer.md).
#include <cstdio>
#include <map>

#include "cli/args.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "cli/report.h"
#include "cli/viewer_page.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/output_file.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/subdiv/mesh_io.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {

int cmd_view(int argc, char** argv) {
  std::string input, output, source, report;
  int rays = 0;
  uint64_t seed = 1;
  ArgParser args("view",
                 "Writes a self-contained HTML page that relights the asset in the browser (WebGL2): sky, sun,\n"
                 "SH, random and environment lights, turned with the camera by mouse; transfer, AO and, with\n"
                 "--source, an error view: the asset's radiance against reference transfer traced on the source\n"
                 "at a grid of points inside every triangle, under the light of the moment.");
  args.positional("ASSET", "an asset written by prtsub bake (.ply, .glb or .gltf)", &input);
  args.option("--output", "PAGE.html", "output page (required)", &output);
  args.alias("-o", "--output");
  args.option("--source", "INPUT", "the mesh the asset was baked from: adds the error view", &source);
  args.option("--rays", "R", "the error view's reference rays per point (0: 8x the asset's)", &rays, 0, 1 << 20);
  args.option("--seed", "S", "the reference's seed", &seed);
  add_report_option(args, report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (output.empty()) throw UsageError("view: missing -o PAGE.html");
  check_writable(output);
  if (!report.empty()) check_writable(report);

  Stopwatch clock;
  const Asset asset = read_asset(input);
  ViewerPageOptions o;
  o.name = input;
  ErrorView error;
  if (!source.empty()) {
    if (asset.channels == 3) throw UsageError("view: the error view is for grey transfer; " + input + " holds RGB transfer (coloured bounces)");
    std::map<std::string, std::string> meta(asset.metadata.begin(), asset.metadata.end());
    const int asset_rays = meta.count("rays") ? std::atoi(meta["rays"].c_str()) : TransferOptions{}.rays;
    const double crease = meta.count("crease_angle") ? std::atof(meta["crease_angle"].c_str()) : LoadOptions{}.crease_angle_deg;
    const Mesh src = load_mesh(source, LoadOptions{crease});
    const RayScene scene(src.positions, position_triangles(src));
    TransferOptions t;
    t.rays = rays > 0 ? rays : 8 * std::max(asset_rays, 1), t.seed = seed;
    error = trace_error_view(asset, scene, t);
    o.error = &error;
  }
  const std::string page = viewer_page(asset, o);
  write_file_atomically(output, page);

  Report r;
  r.set("command", "view");
  r.set("input", input);
  r.set("output", output);
  r.set("vertices", static_cast<int64_t>(asset.transfer.rows()));
  r.set("triangles", asset.triangles.size());
  r.set("order", asset.order);
  r.set("bytes", page.size());
  r.set("reference_rays", error.rays);
  r.set("reference_points", static_cast<int64_t>(error.positions.rows()));
  r.set("reference_segments", error.segments);
  r.set("seconds_total", clock.total());
  r.print(stdout, {"prtsub view: {input} -> {output} ({bytes} bytes)", "  asset:      {triangles} triangles, {vertices} vertices, order {order}",
                   "  error view: {reference_points} points ({reference_segments} segments an edge), {reference_rays} rays each (0: none; --source adds it)"});
  if (!report.empty()) r.write(report);
  return 0;
}

}  // namespace prtsub
