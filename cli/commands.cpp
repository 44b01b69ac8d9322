// The commands: each parses its options into the library's option structs, calls the library,
// and prints what it returns. Heavier commands live beside this file (bench, render, compare,
// eval --fits); run_cli dispatches and turns every exception into one line and an exit code.
#include "cli/commands.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>

#include "cli/args.h"
#include "cli/options.h"
#include "cli/report.h"
#include "cli/summary.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/image_io.h"
#include "prtsub/prt/render.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/mesh_io.h"
#include "prtsub/subdiv/stopwatch.h"
#include "prtsub/version.h"

namespace prtsub {
namespace {

int cmd_bake(int argc, char** argv) {
  BakeCli cli;
  std::string output;
  ArgParser args("bake", "Computes shadowed SH transfer at every vertex and writes a PRT asset (binary PLY).\n"
                         "With --refine, first refines the mesh: adaptively to a triangle budget where the transfer\n"
                         "changes, or uniformly (OpenSubdiv) as a baseline.");
  cli.add_common(args);
  args.option("--output", "ASSET.ply", "output asset (required)", &output);
  args.alias("-o", "--output");
  cli.add_refinement(args);
  cli.add_fit(args);
  if (!args.parse(argc, argv, 2)) return 0;
  if (output.empty()) throw UsageError("bake: missing -o ASSET.ply");
  const BakeOptions options = cli.options();
  check_writable(output);
  if (!cli.report.empty()) check_writable(cli.report);

  Stopwatch clock;
  const Mesh mesh = load_mesh(cli.input, cli.load);
  const double seconds_load = clock.lap();
  StageProgress progress;
  const BakeResult res = bake(mesh, options, progress.callbacks());
  progress.finish();
  clock.lap();
  write_asset(output, res.mesh, res.transfer, res.metadata, options.signal);
  const double seconds_write = clock.lap();

  Report r;
  r.set("command", "bake");
  r.set("input", cli.input);
  r.set("output", output);
  record(r, res, options);
  r.set("seconds_total", clock.total());
  r.set("seconds_load", seconds_load);
  r.set("seconds_write", seconds_write);
  r.set("peak_memory_mib", peak_memory_mib());
  print_bake_summary(r);
  for (const std::string& w : res.warnings) std::fprintf(stderr, "prtsub: warning: %s\n", w.c_str());
  if (!cli.report.empty()) r.write(cli.report);
  return 0;
}

int cmd_inspect(int argc, char** argv) {
  std::string input, report;
  ArgParser args("inspect", "Prints what a PRT asset holds, checks it, and shows the transfer's energy per SH band.");
  args.positional("ASSET", "a .ply asset written by prtsub bake", &input);
  add_report_option(args, report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (!report.empty()) check_writable(report);

  Asset a = read_asset(input);  // throws on NaN/Inf, bad sizes or indices
  const Eigen::Index V = a.transfer.rows();
  size_t bad_normals = 0;
  for (Eigen::Index i = 0; i < V; ++i)
    if (std::abs(a.normals.row(i).norm() - 1.0) > 1e-3) ++bad_normals;
  std::vector<double> band(static_cast<size_t>(a.order), 0.0);
  double total = 0;
  for (int l = 0; l < a.order; ++l) {
    for (int m = -l; m <= l; ++m) band[static_cast<size_t>(l)] += a.transfer.col(sh_index(l, m)).squaredNorm();
    total += band[static_cast<size_t>(l)];
  }
  int order99 = a.order;
  double cumulative = 0;
  for (int l = 0; l < a.order; ++l) {
    cumulative += band[static_cast<size_t>(l)];
    if (total > 0 && cumulative >= 0.99 * total) {
      order99 = l + 1;
      break;
    }
  }
  std::map<std::string, std::string> meta(a.metadata.begin(), a.metadata.end());
  std::printf("prtsub inspect: %s\n", input.c_str());
  const bool ao = a.signal == AssetSignal::Ao;
  std::printf("  vertices:   %lld\n  triangles:  %zu\n", static_cast<long long>(V), a.triangles.size());
  if (ao)
    std::printf("  signal:     ambient occlusion, one ao per vertex, from %.4f to %.4f (mean %.4f)\n",
                V ? a.transfer.minCoeff() * kAoPerT0 : 0.0, V ? a.transfer.maxCoeff() * kAoPerT0 : 0.0,
                V ? a.transfer.mean() * kAoPerT0 : 0.0);
  else
    std::printf("  sh order:   %d (%d coefficients per vertex)\n", a.order, sh_count(a.order));
  for (const auto& [k, v] : a.metadata) std::printf("  meta:       %s %s\n", k.c_str(), v.c_str());
  std::printf("  checks:     finite values, indices in range, %zu of %lld normals not unit length\n", bad_normals,
              static_cast<long long>(V));
  if (!ao) std::printf("  energy by band (sum over vertices of squared coefficients):\n");
  cumulative = 0;
  for (int l = 0; l < a.order && !ao; ++l) {
    cumulative += band[static_cast<size_t>(l)];
    std::printf("    l=%d  %6.3f%%  cumulative %7.3f%%\n", l, total > 0 ? 100 * band[static_cast<size_t>(l)] / total : 0.0,
                total > 0 ? 100 * cumulative / total : 0.0);
  }
  if (!ao)
    std::printf("  order holding 99%% of the energy: %d%s\n", order99,
                order99 < a.order ? " (a lower --order would do for this scene)" : "");
  if (meta.count("sh_order") && meta["sh_order"] != std::to_string(a.order))
    std::printf("  warning:    sh_order comment says %s\n", meta["sh_order"].c_str());

  if (!report.empty()) {
    Report r;
    r.set("command", "inspect");
    r.set("input", input);
    r.set("vertices", static_cast<int64_t>(V));
    r.set("triangles", static_cast<uint64_t>(a.triangles.size()));
    r.set("signal", ao ? "ao" : "transfer");
    r.set("order", a.order);
    r.set("order_99_percent_energy", order99);
    r.set("normals_not_unit", static_cast<uint64_t>(bad_normals));
    for (int l = 0; l < a.order; ++l)
      r.set("energy_fraction_band_" + std::to_string(l), total > 0 ? band[static_cast<size_t>(l)] / total : 0.0);
    r.write(report);
  }
  return bad_normals ? 1 : 0;
}

int cmd_diff(int argc, char** argv) {
  std::string a_path, b_path, heat_path, report;
  ArgParser args("diff", "Compares frame A against reference frame B over pixels covered in both (alpha > 0):\n"
                         "RMSE relative to B's mean, PSNR against B's peak, and an optional false-colour error map.");
  args.positional("A", "the frame to judge (.exr)", &a_path);
  args.positional("B", "the reference frame (.exr)", &b_path);
  args.option("--output", "HEAT.png", "write the error heat map (black 0, yellow 4x RMSE or more; grey uncovered)", &heat_path);
  args.alias("-o", "--output");
  add_report_option(args, report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (!heat_path.empty()) check_writable(heat_path);
  if (!report.empty()) check_writable(report);
  Image a = read_image(a_path), b = read_image(b_path), heat;
  ImageError e;
  try {
    e = image_error(a, b, heat_path.empty() ? nullptr : &heat);
  } catch (const InputError& err) {
    throw InputError(a_path + " vs " + b_path + ": " + err.what());
  }
  if (!heat_path.empty()) write_image(heat_path, heat);
  std::printf("prtsub diff: %s against %s\n  pixels:     %zu covered in both\n  rmse:       %.4f%% of the reference's mean\n  psnr:       %.2f dB\n",
              a_path.c_str(), b_path.c_str(), e.pixels, 100 * e.rmse_relative, e.psnr_db);
  if (!report.empty()) {
    Report r;
    r.set("command", "diff");
    r.set("a", a_path);
    r.set("b", b_path);
    r.set("pixels", static_cast<uint64_t>(e.pixels));
    r.set("rmse_relative", e.rmse_relative);
    r.set("rmse_percent", 100 * e.rmse_relative);
    r.set("psnr_db", e.psnr_db);
    r.write(report);
  }
  return 0;
}

int cmd_eval(int argc, char** argv) {
  std::string input, source, report;
  ReferenceOptions ro;
  int points = static_cast<int>(ro.points), rays = 0;
  ArgParser args("eval",
                 "Surface RMS transfer error of an asset, as a percentage of ||t_unshadowed||, at seeded area-\n"
                 "stratified points on its source surface against a reference with many more rays. Each point is\n"
                 "located in the asset through source_face, so any refinement can be judged on the same points.");
  args.positional("ASSET", "a .ply asset written by prtsub bake (transfer or ao)", &input);
  args.option("--source", "INPUT", "the mesh the asset was baked from (required)", &source);
  args.option("--points", "N", "reference points", &points, 1, 10000000);
  args.option("--rays", "R", "reference rays per point (0: 8x the asset's rays)", &rays, 0, 1 << 20);
  args.option("--seed", "S", "reference seed; keep it fixed to compare assets", &ro.seed);
  args.option("--threads", "T", "worker threads, 0 for every core", &ro.threads, 0, 1024);
  add_report_option(args, report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (source.empty()) throw UsageError("eval: missing --source INPUT");
  if (!report.empty()) check_writable(report);
  Stopwatch clock;
  Asset asset = read_asset(input);
  std::map<std::string, std::string> meta(asset.metadata.begin(), asset.metadata.end());
  const int asset_rays = meta.count("rays") ? std::atoi(meta["rays"].c_str()) : 256;
  const double crease = meta.count("crease_angle") ? std::atof(meta["crease_angle"].c_str()) : LoadOptions{}.crease_angle_deg;
  ro.points = static_cast<size_t>(points);
  ro.rays = rays > 0 ? rays : 8 * std::max(asset_rays, 1);
  ro.order = asset.order;
  Mesh src = load_mesh(source, LoadOptions{crease});
  RayScene scene(src.positions, position_triangles(src));
  Reference ref = make_reference(src, scene, ro);
  const double t_ref = clock.lap();
  EvalResult e = evaluate(ref, asset.positions, asset.triangles, asset.source_face, asset.transfer);
  std::printf("prtsub eval: %s against %s\n", input.c_str(), source.c_str());
  std::printf("  asset:      %zu triangles, order %d, %d rays per vertex\n", asset.triangles.size(), asset.order, asset_rays);
  std::printf("  reference:  %zu points, %d rays each (%.2f s); its own noise floor %.3f%%\n", e.points, ro.rays, t_ref,
              e.noise_floor_percent);
  std::printf("  error:      RMS %.3f%%, 95th percentile %.3f%% of ||t_unshadowed||\n", e.rms_percent, e.p95_percent);
  if (e.unlocated) std::printf("  warning:    %zu reference points had no face in the asset\n", e.unlocated);
  if (!report.empty()) {
    Report r;
    r.set("command", "eval");
    r.set("input", input);
    r.set("source", source);
    r.set("triangles", static_cast<uint64_t>(asset.triangles.size()));
    r.set("rms_percent", e.rms_percent);
    r.set("p95_percent", e.p95_percent);
    r.set("noise_floor_percent", e.noise_floor_percent);
    r.set("reference_points", static_cast<uint64_t>(e.points));
    r.set("reference_rays", ro.rays);
    r.set("unlocated_points", static_cast<uint64_t>(e.unlocated));
    r.set("seconds_reference", t_ref);
    r.write(report);
  }
  return 0;
}

const char* kUsage =
    "usage: prtsub COMMAND [options]\n"
    "\n"
    "Prepares meshes for diffuse precomputed radiance transfer (PRT).\n"
    "\n"
    "commands:\n"
    "  bake      compute per-vertex shadowed SH transfer and write a PRT asset\n"
    "  inspect   print and check what an asset holds, with its energy per SH band\n"
    "  bench     time the transfer stage against a bare Embree occlusion loop\n"
    "  compare   uniform against adaptive refinement: tables, plots and relit frames\n"
    "  eval      surface RMS transfer error of an asset against a high-ray reference;\n"
    "            eval --fits INPUT: point, average and least-squares values on one mesh\n"
    "  render    relight an asset into a frame (Gouraud, or the per-pixel reference)\n"
    "  diff      compare two frames: relative RMSE, PSNR and an error heat map\n"
    "\n"
    "prtsub COMMAND --help shows a command's options. Docs: docs/ in the source tree.\n";

}  // namespace

int run_cli(int argc, char** argv) {
  try {
    if (argc < 2) {
      std::fputs(kUsage, stderr);
      return 2;
    }
    const std::string command = argv[1];
    if (command == "--help" || command == "-h" || command == "help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (command == "--version") {
      std::printf("prtsub %s\n", kVersion);
      return 0;
    }
    if (command == "bake") return cmd_bake(argc, argv);
    if (command == "inspect") return cmd_inspect(argc, argv);
    if (command == "bench") return cmd_bench(argc, argv);
    if (command == "render") return cmd_render(argc, argv);
    if (command == "eval") {
      for (int i = 2; i < argc; ++i)
        if (std::strcmp(argv[i], "--fits") == 0) return cmd_eval_fits(argc, argv);
      return cmd_eval(argc, argv);
    }
    if (command == "compare") return cmd_compare(argc, argv);
    if (command == "diff") return cmd_diff(argc, argv);
    throw UsageError("unknown command '" + command + "' (try prtsub --help)");
  } catch (const UsageError& e) {
    std::fprintf(stderr, "prtsub: error: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "prtsub: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "prtsub: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace prtsub
