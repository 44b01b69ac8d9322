// The commands: each parses its options into the library's option structs, calls the library,
// and prints what it returns. Heavier commands live beside this file (bench, render, compare,
// eval --fits); run_cli dispatches and turns every exception into one line and an exit code.
#include "cli/commands.h"
#include "cli/images.h"

#include <cmath>
#include <filesystem>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>

#include "cli/args.h"
#include "cli/escape.h"
#include "cli/options.h"
#include "cli/report.h"
#include "cli/summary.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/batch.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/output_file.h"
#include "prtsub/prt/gltf.h"
#include "prtsub/prt/render.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/sh.h"
#include "prtsub/prt/shard.h"
#include "prtsub/subdiv/mesh_io.h"
#include "prtsub/subdiv/ply.h"
#include "prtsub/subdiv/stopwatch.h"
#include "prtsub/version.h"

namespace prtsub {
namespace {

// bake with several inputs, a folder or an @list: one process, DIR/NAME.EXT per input, a report
// beside each asset and DIR/batch.csv and batch.json for the whole batch.
int bake_many(const BakeCli& cli, const std::vector<std::string>& inputs, const std::string& out_dir, const BakeOptions& options,
              const GltfOptions& gltf, const std::string& format, bool force) {
  Stopwatch clock;
  const std::vector<BatchJob> jobs = batch_jobs(inputs, out_dir, "." + format);
  if (jobs.empty()) throw InputError("bake: no mesh files (.obj, .ply, .off, .stl) in the inputs");
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw IoError(out_dir + ": cannot create the output folder (" + ec.message() + ")");
  BatchOptions b;
  b.bake = options, b.load = cli.load, b.gltf = gltf, b.force = force;
  BatchProgress progress;
  progress.done = [&](size_t i, size_t total, const BatchEntry& e, const BakeResult* result) {
    if (e.status == BatchStatus::Failed) {
      std::fprintf(stderr, "prtsub: error: %s\n", e.error.c_str());
      std::printf("[%zu/%zu] %s: failed\n", i + 1, total, e.job.input.c_str());
    } else if (e.status == BatchStatus::Skipped) {
      std::printf("[%zu/%zu] %s: up to date, skipped (%s)\n", i + 1, total, e.job.input.c_str(), e.job.output.c_str());
    } else {
      std::printf("[%zu/%zu] %s -> %s: %zu triangles, %.3g rays, %.2f s\n", i + 1, total, e.job.input.c_str(), e.job.output.c_str(),
                  e.triangles_out, static_cast<double>(e.rays), e.seconds);
    }
    std::fflush(stdout);
    if (result) {  // the same report a single bake writes, beside the asset
      Report r;
      r.set("command", "bake");
      r.set("input", e.job.input);
      r.set("output", e.job.output);
      record(r, *result, options);
      r.set("bake_key", e.key);
      r.set("seconds_total", e.seconds);
      std::filesystem::path report = e.job.output;
      r.write(report.replace_extension(".report.json").string());
    }
  };
  const std::vector<BatchEntry> entries = bake_batch(jobs, b, progress);

  size_t baked = 0, skipped = 0, failed = 0;
  uint64_t rays = 0;
  std::string csv = "input,output,status,triangles_in,triangles_out,vertices_out,rays,seconds,key,error\n";
  std::string json = "{\n  \"assets\": [";
  auto csv_field = [](const std::string& v) {
    std::string q = "\"";
    for (char ch : v) q += ch == '"' ? std::string("\"\"") : std::string(1, ch == '\n' ? ' ' : ch);
    return q + "\"";
  };
  char number[64];
  for (size_t i = 0; i < entries.size(); ++i) {
    const BatchEntry& e = entries[i];
    baked += e.status == BatchStatus::Baked, skipped += e.status == BatchStatus::Skipped, failed += e.status == BatchStatus::Failed;
    rays += e.rays;
    std::snprintf(number, sizeof number, "%.6g", e.seconds);
    csv += csv_field(e.job.input) + "," + csv_field(e.job.output) + "," + batch_status_name(e.status) + "," + std::to_string(e.triangles_in) +
           "," + std::to_string(e.triangles_out) + "," + std::to_string(e.vertices_out) + "," + std::to_string(e.rays) + "," + number + "," +
           e.key + "," + csv_field(e.error) + "\n";
    json += std::string(i ? "," : "") + "\n    {\"input\": " + json_quote(e.job.input) + ", \"output\": " + json_quote(e.job.output) +
            ", \"status\": \"" + batch_status_name(e.status) + "\", \"triangles_in\": " + std::to_string(e.triangles_in) +
            ", \"triangles_out\": " + std::to_string(e.triangles_out) + ", \"vertices_out\": " + std::to_string(e.vertices_out) +
            ", \"rays\": " + std::to_string(e.rays) + ", \"seconds\": " + number + ", \"key\": \"" + e.key + "\", \"error\": " +
            json_quote(e.error) + "}";
  }
  json += "\n  ]\n}\n";
  write_file_atomically(out_dir + "/batch.csv", csv);
  write_file_atomically(out_dir + "/batch.json", json);
  Report r;
  r.set("command", "bake");
  r.set("output", out_dir);
  r.set("assets", entries.size());
  r.set("baked", baked);
  r.set("skipped", skipped);
  r.set("failed", failed);
  r.set("rays", rays);
  r.set("seconds_total", clock.total());
  r.set("peak_memory_mib", peak_memory_mib());
  r.print(stdout, {"prtsub bake: {assets} assets -> {output}: {baked} baked, {skipped} up to date, {failed} failed, {seconds_total:2} s "
                   "(batch.csv, batch.json)"});
  if (!cli.report.empty()) r.write(cli.report);
  return failed ? 1 : 0;
}

// The content key of a sharded bake is the asset's with this in place of the output's format:
// its parts do not depend on the format the merge writes.
constexpr const char* kPartFormat = "parts.part";

// The bake's arguments for a part's header, so that prtsub merge needs only the folder: every
// argument but the input, the outputs and the shard's own (--shard, --parts, --phase).
std::vector<std::string> recorded_arguments(int argc, char** argv, const std::string& input) {
  static const char* const kDropped[] = {"--shard", "--parts", "--phase", "-o", "--output", "--report"};
  std::vector<std::string> out;
  bool input_seen = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    bool dropped = false;
    for (const char* d : kDropped) {
      if (a == d) dropped = true, ++i;  // and its value
      else if (a.rfind(std::string(d) + "=", 0) == 0) dropped = true;
    }
    if (dropped) continue;
    if (!input_seen && a == input) {
      input_seen = true;
      continue;
    }
    out.push_back(a);
  }
  return out;
}

// bake --shard I/N --parts DIR: one shard's slice of one phase, written to DIR.
int bake_shard_cli(const BakeCli& cli, int argc, char** argv, const std::string& shard, const std::string& parts, int phase, bool several) {
  if (several || cli.input.rfind('@', 0) == 0) throw UsageError("bake: --shard takes one input mesh");
  if (parts.empty()) throw UsageError("bake: --shard needs --parts DIR, where the parts go");
  const BakeOptions options = cli.options();
  if (!cli.report.empty()) check_writable(cli.report);
  const auto [index, count] = parse_shard(shard);
  const std::string bytes = read_file_bytes(cli.input);
  const Mesh mesh = parse_mesh(bytes, cli.input, cli.load);
  BatchOptions key_options;
  key_options.bake = options, key_options.load = cli.load;
  ShardOptions s;
  s.shard = index, s.shards = count, s.phase = phase, s.dir = parts;
  s.key = bake_key(bytes, key_options, kPartFormat);
  std::error_code ec;
  // The input as given (the asset records it as its source) and where it was given from.
  s.notes.push_back({"input", cli.input});
  s.notes.push_back({"cwd", std::filesystem::current_path(ec).string()});
  for (const std::string& a : recorded_arguments(argc, argv, cli.input)) {
    if (a.find('\n') != std::string::npos) throw UsageError("bake: an argument with a line break cannot be recorded in a part");
    s.notes.push_back({"arg", a});
  }
  StageProgress progress;
  const ShardResult r = bake_shard(mesh, options, s, progress.callbacks());
  progress.finish();
  Report rep;
  rep.set("command", "bake");
  rep.set("input", cli.input);
  rep.set("parts", parts);
  rep.set("shard", std::to_string(index) + "/" + std::to_string(count));
  rep.set("phase", r.phase);
  rep.set("phases", r.phases);
  rep.set("nothing_left", r.nothing_left);
  rep.set("part", r.path);
  rep.set("points", r.points);
  rep.set("rays", r.rays);
  rep.set("bytes", r.bytes);
  rep.set("seconds_total", r.seconds);
  rep.set("peak_memory_mib", peak_memory_mib());
  if (r.nothing_left)
    rep.print(stdout, {"prtsub bake: shard {shard}: all {phases} phases traced; merge with prtsub merge {parts} -o ASSET"});
  else
    rep.print(stdout, {"prtsub bake: shard {shard}, phase {phase} of {phases}: {points} points, {rays} rays in {seconds_total:2} s -> {part} "
                       "({bytes} bytes)"});
  if (!cli.report.empty()) rep.write(cli.report);
  return 0;
}

int cmd_bake(int argc, char** argv) {
  BakeCli cli;
  std::string output, up = "y", format = "ply";
  std::vector<std::string> more;
  bool force = false;
  GltfOptions gltf;
  ArgParser args("bake", "Computes shadowed SH transfer at every vertex and writes a PRT asset: a binary PLY, or glTF 2.0\n"
                         "when ASSET ends in .glb or .gltf. With --refine, first refines the mesh: adaptively to a\n"
                         "triangle budget where the transfer changes, or uniformly (OpenSubdiv) as a baseline.\n"
                         "Several inputs, a folder or @LIST (one path per line) bake in one process into -o DIR.");
  cli.add_common(args);
  args.rest("INPUT", &more);
  args.option("--output", "ASSET|DIR", "output asset, .ply, .glb or .gltf; a folder for several inputs (required)", &output);
  args.alias("-o", "--output");
  args.option("--format", "ply|glb|gltf", "several inputs: the assets' format [default ply]", &format);
  args.flag("--force", "several inputs: bake even the assets that are up to date", &force);
  args.option("--up", "y|z", "glTF: the input's up axis; z rotates positions, normals and SH to glTF's +Y up (default y)", &up);
  args.flag("--quantize", "glTF: transfer as normalized SHORT with a scale per coefficient (half the size)", &gltf.quantize);
  args.flag("--compress", "glTF: EXT_meshopt_compression (required by the file; most engines and three.js decode it)", &gltf.compress);
  cli.add_refinement(args);
  cli.add_fit(args);
  cli.add_basis(args);
  std::string stage = "all", shard, parts;
  int phase = 0;
  bool print_phases = false;
  args.option("--stage", "all|refine", "refine: stop after refinement (or simplification) and write the mesh with its point values,\n"
              "a .ply to bake again: a sharded bake needs a fixed mesh", &stage);
  args.option("--shard", "I/N", "trace shard I of N of one phase of this bake into --parts DIR; then prtsub merge DIR (docs/shards.md)", &shard);
  args.option("--parts", "DIR", "the shards' part files: with --shard, where this shard writes; without, the parts to merge into -o ASSET", &parts);
  args.option("--phase", "Q", "with --shard: the phase to trace (default: the first this shard has not traced)", &phase, 1, 64);
  args.flag("--shard-phases", "print how many phases a sharded bake with these options has, and exit", &print_phases);
  if (!args.parse(argc, argv, 2)) return 0;
  if (stage != "all" && stage != "refine") throw UsageError("bake: --stage takes all or refine, not '" + stage + "'");
  if (print_phases) {
    std::printf("%d\n", shard_phases(cli.options()));
    return 0;
  }
  if (!shard.empty()) return bake_shard_cli(cli, argc, argv, shard, parts, phase, !more.empty());
  if (phase) throw UsageError("bake: --phase is for --shard");
  if (output.empty()) throw UsageError("bake: missing -o ASSET.ply");
  if (up != "y" && up != "z") throw UsageError("bake: --up takes y or z, not '" + up + "'");
  gltf.up = parse_up_axis(up);
  std::error_code ec;
  if (!more.empty() || cli.input.rfind('@', 0) == 0 || std::filesystem::is_directory(cli.input, ec)) {
    if (format != "ply" && format != "glb" && format != "gltf") throw UsageError("--format: takes ply, glb or gltf, not '" + format + "'");
    if (format == "ply" && (gltf.quantize || gltf.compress || gltf.up != UpAxis::Y))
      throw UsageError("bake: --up, --quantize and --compress are for glTF outputs (--format glb or gltf)");
    if (!cli.report.empty()) check_writable(cli.report);
    more.insert(more.begin(), cli.input);
    return bake_many(cli, more, output, cli.options(), gltf, format, force);
  }
  const bool to_gltf = is_gltf_path(output);
  if (!to_gltf && (gltf.quantize || gltf.compress || gltf.up != UpAxis::Y))
    throw UsageError("bake: --up, --quantize and --compress are for glTF outputs (-o ASSET.glb or .gltf)");
  BakeOptions options = cli.options();
  options.refine_only = stage == "refine";
  if (options.refine_only && to_gltf) throw UsageError("bake: --stage refine writes a .ply (a mesh to bake again)");
  if (options.refine_only && !parts.empty()) throw UsageError("bake: --stage refine is not sharded (its refinement is one queue)");
  check_writable(output);
  if (!cli.report.empty()) check_writable(cli.report);

  Stopwatch clock;
  const std::string bytes = read_file_bytes(cli.input);
  const Mesh mesh = parse_mesh(bytes, cli.input, cli.load);
  const double seconds_load = clock.lap();
  // The batch's content key, so that a later batch over the same inputs skips this asset.
  BatchOptions key_options;
  key_options.bake = options, key_options.load = cli.load, key_options.gltf = gltf;
  StageProgress progress;
  BakeResult res = parts.empty() ? bake(mesh, options, progress.callbacks())
                                 : bake_merged(mesh, options, parts, bake_key(bytes, key_options, kPartFormat), progress.callbacks());
  progress.finish();
  const std::string key = bake_key(bytes, key_options, output);
  res.metadata.push_back({"bake_key", key});
  clock.lap();
  if (to_gltf) write_gltf_asset(output, res.mesh, res.transfer, res.metadata, options.signal, gltf, res.albedo);
  else write_asset(output, res.mesh, res.transfer, res.metadata, options.signal, res.albedo);
  const double seconds_write = clock.lap();

  Report r;
  r.set("command", "bake");
  r.set("input", cli.input);
  r.set("output", output);
  record(r, res, options);
  r.set("bake_key", key);
  if (!parts.empty()) {  // a merge: the rays were the shards'
    const std::vector<PartHeader> headers = list_parts(parts);
    r.set("merged_parts", parts);
    r.set("merged_shards", size_t(headers.empty() ? 0 : headers.front().shards));
    r.set("merged_phases", size_t(shard_phases(options)));
  }
  r.set("seconds_total", clock.total());
  r.set("seconds_load", seconds_load);
  r.set("seconds_write", seconds_write);
  r.set("peak_memory_mib", peak_memory_mib());
  print_bake_summary(r);
  for (const std::string& w : res.warnings) std::fprintf(stderr, "prtsub: warning: %s\n", w.c_str());
  if (!cli.report.empty()) r.write(cli.report);
  return 0;
}

// merge DIR -o ASSET: the bake the parts were traced for, with its input and options read
// from them, run as bake INPUT OPTIONS --parts DIR -o ASSET.
int cmd_merge(int argc, char** argv) {
  std::string dir, output, report;
  ArgParser args("merge", "Gathers the part files a sharded bake (bake --shard I/N --parts DIR) wrote, checks that they\n"
                          "belong together, runs the fit and writes the asset: bit-identical to the same bake in one process.\n"
                          "The input mesh and the options are the ones recorded in the parts.");
  args.positional("DIR", "the parts' folder", &dir);
  args.option("--output", "ASSET", "output asset, .ply, .glb or .gltf (required)", &output);
  args.alias("-o", "--output");
  args.option("--report", "FILE", "write a JSON report of the bake", &report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (dir.empty()) throw UsageError("merge: missing the parts' folder");
  if (output.empty()) throw UsageError("merge: missing -o ASSET");
  const std::vector<PartHeader> parts = list_parts(dir);
  if (parts.empty()) throw InputError(dir + ": holds no parts (*.part) to merge");
  std::vector<std::string> a = {argv[0], "bake"};
  std::string input, cwd;
  for (const auto& [name, value] : parts.front().notes) {
    if (name == "input") input = value;
    if (name == "cwd") cwd = value;
    if (name == "arg") a.push_back(value);
  }
  if (input.empty()) throw InputError(parts.front().path + ": does not name its input mesh (bake INPUT OPTIONS --parts DIR -o ASSET merges it)");
  a.insert(a.begin() + 2, input);
  // The bake runs where the shards ran, so that the input (and the source the asset records)
  // is the path they were given; the folder and the outputs are the caller's.
  namespace fs = std::filesystem;
  std::error_code ec;
  dir = fs::absolute(dir, ec).string(), output = fs::absolute(output, ec).string();
  if (!report.empty()) report = fs::absolute(report, ec).string();
  if (!cwd.empty() && fs::path(input).is_relative()) {
    fs::current_path(cwd, ec);
    if (ec || !fs::exists(input, ec))
      throw InputError(parts.front().path + ": its input " + input + " (from " + cwd +
                       ") is not there; bake INPUT OPTIONS --parts DIR -o ASSET merges with the input named");
  }
  for (const char* x : {"--parts", dir.c_str(), "-o", output.c_str()}) a.push_back(x);
  if (!report.empty()) a.push_back("--report"), a.push_back(report);
  std::vector<char*> v;
  for (std::string& x : a) v.push_back(x.data());
  v.push_back(nullptr);
  return cmd_bake(int(a.size()), v.data());
}

// inspect: what an asset holds, checked, with its transfer's energy per SH band.
Report inspect_record(const std::string& input, const Asset& a) {
  const Eigen::Index V = a.transfer.rows();
  const bool ao = a.signal == AssetSignal::Ao;
  size_t bad_normals = 0;
  for (Eigen::Index i = 0; i < V; ++i)
    if (std::abs(a.normals.row(i).norm() - 1.0) > 1e-3) ++bad_normals;
  std::vector<double> band(static_cast<size_t>(a.order), 0.0);
  double total = 0;
  const Eigen::Index stride = ao ? 1 : a.transfer.cols() / a.channels;  // RGB: every channel's bands
  for (int l = 0; l < a.order; ++l) {
    for (int c = 0; c < a.channels; ++c)
      for (int m = -l; m <= l; ++m) band[static_cast<size_t>(l)] += a.transfer.col(c * stride + sh_index(l, m)).squaredNorm();
    total += band[static_cast<size_t>(l)];
  }
  Report r;
  r.set("command", "inspect");
  r.set("input", input);
  r.set("vertices", static_cast<int64_t>(V));
  r.set("triangles", a.triangles.size());
  r.set("signal", ao ? "ao" : "transfer");
  r.set("order", a.order);
  r.set("coefficients", sh_count(a.order));
  r.set("lobes", static_cast<int64_t>(a.sg.cols()));
  r.set("basis", a.sg.cols() > 0 ? "sg:" + std::to_string(a.sg.cols()) : std::string("sh"));
  r.set("channels", a.channels);
  r.set("channels_text", a.channels == 3 ? ", per channel: RGB transfer" : "");
  r.set("albedo", a.albedo.rows() > 0 ? "; albedo per vertex (albedo_r/g/b)" : "");
  r.set("normals_not_unit", bad_normals);
  if (ao && V > 0) {
    r.set("ao_min", a.transfer.minCoeff() * kAoPerT0);
    r.set("ao_max", a.transfer.maxCoeff() * kAoPerT0);
    r.set("ao_mean", a.transfer.mean() * kAoPerT0);
  }
  int order99 = a.order;  // the fewest bands that hold 99% of the energy
  double cumulative = 0;
  for (int l = 0; l < a.order; ++l) {
    cumulative += band[static_cast<size_t>(l)];
    if (total > 0 && cumulative >= 0.99 * total && order99 == a.order) order99 = l + 1;
    r.set("energy_fraction_band_" + std::to_string(l), total > 0 ? band[static_cast<size_t>(l)] / total : 0.0);
    r.set("energy_cumulative_band_" + std::to_string(l), total > 0 ? cumulative / total : 0.0);
  }
  r.set("order_99_percent_energy", order99);
  return r;
}

int cmd_inspect(int argc, char** argv) {
  std::string input, report;
  ArgParser args("inspect", "Prints what a PRT asset holds, checks it, and shows the transfer's energy per SH band.");
  args.positional("ASSET", "an asset written by prtsub bake (.ply, .glb or .gltf)", &input);
  add_report_option(args, report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (!report.empty()) check_writable(report);

  const Asset a = read_asset(input);  // throws on NaN/Inf, bad sizes or indices
  const Report r = inspect_record(input, a);
  const bool ao = a.signal == AssetSignal::Ao;
  const bool lobes = a.sg.cols() > 0;
  r.print(stdout, {"prtsub inspect: {input}", "  vertices:   {vertices}", "  triangles:  {triangles}",
                   ao      ? "  signal:     ambient occlusion, one ao per vertex, from {ao_min:4} to {ao_max:4} (mean {ao_mean:4})"
                   : lobes ? "  basis:      {lobes} spherical-Gaussian lobes per vertex, relit through SH order {order} (exact for its lights)"
                           : "  sh order:   {order} ({coefficients} coefficients per vertex{channels_text}){albedo}"});
  for (const auto& [k, v] : a.metadata) std::printf("  meta:       %s %s\n", k.c_str(), v.c_str());
  r.print(stdout, {"  checks:     finite values, indices in range, {normals_not_unit} of {vertices} normals not unit length"});
  if (!ao) {
    std::printf(lobes ? "  energy by band of the lobes' SH equivalent (sum over vertices of squared coefficients):\n"
                      : "  energy by band (sum over vertices of squared coefficients):\n");
    for (int l = 0; l < a.order; ++l) {
      const std::string b = std::to_string(l);
      std::printf("%s\n", r.format("    l=" + b + "  {energy_fraction_band_" + b + ":%3}  cumulative {energy_cumulative_band_" + b + ":%3}").c_str());
    }
    const bool lower = r.number("order_99_percent_energy") < a.order && !lobes;
    std::printf("%s\n", r.format(std::string("  order holding 99% of the energy: {order_99_percent_energy}") +
                                 (lower ? " (a lower --order would do for this scene)" : "")).c_str());
  }
  const std::map<std::string, std::string> meta(a.metadata.begin(), a.metadata.end());
  if (meta.count("sh_order") && meta.at("sh_order") != std::to_string(a.order))
    std::printf("  warning:    sh_order comment says %s\n", meta.at("sh_order").c_str());
  if (!report.empty()) r.write(report);
  if (r.number("normals_not_unit") > 0) {
    // A failed check is a failure like any other: its one line on stderr, whatever stdout shows.
    std::fprintf(stderr, "%s\n", r.format("prtsub: error: {input}: {normals_not_unit} of {vertices} normals are not unit length").c_str());
    return 1;
  }
  return 0;
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
  const Image a = cli_read_image(a_path), b = cli_read_image(b_path);
  Image heat;
  ImageError e;
  try {
    e = image_error(a, b, heat_path.empty() ? nullptr : &heat);
  } catch (const InputError& err) {
    throw InputError(a_path + " vs " + b_path + ": " + err.what());
  }
  if (!heat_path.empty()) cli_write_image(heat_path, heat);
  Report r;
  r.set("command", "diff");
  r.set("a", a_path);
  r.set("b", b_path);
  r.set("pixels", e.pixels);
  r.set("rmse_relative", e.rmse_relative);
  r.set("rmse_percent", 100 * e.rmse_relative);
  r.set("rmse_rms_relative", e.rmse_rms_relative);  // of the reference's RMS: for lights that shade negative
  r.set("psnr_db", e.psnr_db);
  r.print(stdout, {"prtsub diff: {a} against {b}", "  pixels:     {pixels} covered in both",
                   "  rmse:       {rmse_percent:4}% of the reference's mean", "  psnr:       {psnr_db:2} dB"});
  if (!report.empty()) r.write(report);
  return 0;
}

int cmd_eval(int argc, char** argv) {
  std::string input, source, report;
  ReferenceOptions ro;
  int rays = 0;
  ArgParser args("eval",
                 "Surface RMS transfer error of an asset, as a percentage of ||t_unshadowed||, at seeded area-\n"
                 "stratified points on its source surface against a reference with many more rays. Each point is\n"
                 "located in the asset through source_face, so any refinement can be judged on the same points;\n"
                 "in a simplified asset (whose faces no longer lie in the source's), at its closest point.\n"
                 "An asset baked from another mesh of the same object (a level of detail made by another tool)\n"
                 "is judged with --locate closest.");
  args.positional("ASSET", "an asset written by prtsub bake (.ply, .glb or .gltf; transfer or ao)", &input);
  args.option("--source", "INPUT", "the mesh the asset was baked from (required)", &source);
  args.option("--points", "N", "reference points", &ro.points, size_t(1), size_t(10000000));
  args.option("--rays", "R", "reference rays per point (0: 8x the asset's rays)", &rays, 0, 1 << 20);
  args.option("--seed", "S", "reference seed; keep it fixed to compare assets", &ro.seed);
  args.option("--paths", "P", "an asset baked with --bounces: paths per point tracing the reference's bounced light (0: --rays)",
              &ro.paths, 0, 1 << 20);
  int reference_bounces = -1;
  std::string reference_albedo;
  args.option("--reference-bounces", "N", "judge against N bounces instead of the asset's own count (0: direct light only)",
              &reference_bounces, 0, 64);
  args.option("--reference-albedo", "A|R,G,B|vertex|map:PATH", "the reference bounces at this albedo instead of the asset's (default\n"
              "the asset's, else 0.8); a coloured one judges a grey asset as the same in every channel: what\n"
              "baking without colour costs", &reference_albedo);
  std::string locate = "auto";
  args.option("--locate", "auto|source-face|closest", "how a reference point finds its place in the asset: through source_face,\n"
              "or at its closest point facing its way; auto: closest for a simplified asset [default auto]", &locate);
  add_threads_option(args, ro.threads);
  add_report_option(args, report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (source.empty()) throw UsageError("eval: missing --source INPUT");
  if (locate != "auto" && locate != "source-face" && locate != "closest")
    throw UsageError("eval: --locate must be auto, source-face or closest, got '" + locate + "'");
  if (!report.empty()) check_writable(report);
  Stopwatch clock;
  const Asset asset = read_asset(input);
  std::map<std::string, std::string> meta(asset.metadata.begin(), asset.metadata.end());
  const int asset_rays = meta.count("rays") ? std::atoi(meta["rays"].c_str()) : TransferOptions{}.rays;
  const double crease = meta.count("crease_angle") ? std::atof(meta["crease_angle"].c_str()) : LoadOptions{}.crease_angle_deg;
  ro.rays = rays > 0 ? rays : 8 * std::max(asset_rays, 1);
  ro.order = asset.order;
  // A bounced asset is judged against bounced light at its own count and albedo.
  const AssetBounces bounces = asset_bounces(asset, input);
  ro.bounces = bounces.bounces, ro.albedo = bounces.albedo;
  // How far from interreflected light a direct-only asset is, say: another count than the asset's.
  if (reference_bounces >= 0) ro.bounces = reference_bounces;
  AlbedoSpec reference_spec = bounces.spec;
  if (!reference_albedo.empty()) {
    try {
      if (reference_albedo.rfind("map:", 0) == 0) reference_spec = AlbedoSpec{}, reference_spec.source = AlbedoSource::Map, reference_spec.map = reference_albedo.substr(4);
      else reference_spec = parse_albedo(reference_albedo);
    } catch (const InputError& e) {
      throw UsageError(std::string("--reference-albedo: ") + e.what());
    }
    if (!reference_spec.coloured()) ro.albedo = reference_spec.constant.x();
  }
  const Mesh src = load_mesh(source, LoadOptions{crease});
  // Coloured bounces: the reference bounces with that albedo over the source, in RGB.
  const bool coloured = asset.channels == 3 || (!reference_albedo.empty() && reference_spec.coloured());
  if (coloured) {
    if (asset.signal == AssetSignal::Ao) throw UsageError("eval: a coloured --reference-albedo is for transfer assets");
    if (!reference_spec.coloured()) throw UsageError("eval: " + input + " holds coloured bounces; judge it against a coloured --reference-albedo");
    try {
      ro.colour = std::make_shared<const AlbedoField>(src, cli_load_albedo(reference_spec));
    } catch (const InputError& e) {
      throw InputError(source + ": " + e.what());
    }
  }
  // A grey asset against a coloured reference: the same transfer in every channel.
  const RowMatrixXd judged = coloured && asset.channels == 1 ? RowMatrixXd(asset.transfer.replicate(1, 3)) : asset.transfer;
  const RayScene scene(src.positions, position_triangles(src));
  Progress progress("reference", static_cast<size_t>(ro.points) * (ro.bounces > 0 ? 2 : 1), stderr_is_terminal());
  const Reference ref = make_reference(src, scene, ro, [&](size_t n) { progress.add(n); });
  progress.finish();
  const double t_ref = clock.lap();
  // A simplified asset's faces do not lie in the source's: locate by closest point. So too for an
  // asset baked from another mesh of the object, whose source_face numbers that mesh's faces.
  const bool simplified = meta.count("simplified") > 0;
  const bool closest = locate == "closest" || (locate == "auto" && simplified);
  const EvalResult e = closest ? evaluate_by_closest_point(ref, asset.positions, asset.triangles, judged, ro.threads)
                               : evaluate(ref, asset.positions, asset.triangles, asset.source_face, judged);
  Report r;
  r.set("command", "eval");
  r.set("location", !closest ? "source_face" : simplified ? "closest point (a simplified asset)" : "closest point");
  r.set("input", input);
  r.set("source", source);
  r.set("triangles", asset.triangles.size());
  r.set("order", asset.order);
  r.set("asset_rays", asset_rays);
  r.set("rms_percent", e.rms_percent);
  r.set("p95_percent", e.p95_percent);
  r.set("noise_floor_percent", e.noise_floor_percent);
  r.set("reference_points", e.points);
  r.set("reference_rays", ro.rays);
  r.set("unlocated_points", e.unlocated);
  r.set("reference_bounces", ref.bounces);
  r.set("asset_bounces", bounces.bounces);
  r.set("channels", asset.channels);
  if (ref.bounces > 0) {
    if (ro.colour) r.set("albedo", albedo_description(reference_spec));
    else r.set("albedo", ro.albedo);
    r.set("reference_paths", ref.paths);
    r.set("seconds_reference_bounces", ref.seconds_bounce);
  }
  r.set("seconds_reference", t_ref);
  r.print(stdout, {"prtsub eval: {input} against {source}", "  asset:      {triangles} triangles, order {order}, {asset_rays} rays per vertex",
                   "  reference:  {reference_points} points, {reference_rays} rays each ({seconds_reference:2} s); its own noise "
                   "floor {noise_floor_percent:3}%; located by {location}"});
  if (ref.bounces > 0)
    r.print(stdout, {"  bounced:    {reference_bounces} bounces at albedo {albedo}: {reference_paths} paths per point through the source "
                     "({seconds_reference_bounces:2} s), not the asset"});
  r.print(stdout, {"  error:      RMS {rms_percent:3}%, 95th percentile {p95_percent:3}% of ||t_unshadowed||"});
  if (e.unlocated)
    r.print(stdout, {closest ? "  warning:    {unlocated_points} reference points had no face in the asset"
                             : "  warning:    {unlocated_points} reference points had no face in the asset (baked from another mesh? "
                               "--locate closest)"});
  if (!report.empty()) r.write(report);
  return 0;
}

const char* kUsage =
    "usage: prtsub COMMAND [options]\n"
    "\n"
    "Prepares meshes for diffuse precomputed radiance transfer (PRT).\n"
    "\n"
    "commands:\n"
    "  bake      compute per-vertex shadowed SH transfer and write a PRT asset\n"
    "  merge     gather a sharded bake's parts (bake --shard I/N --parts DIR), fit, write the asset\n"
    "  inspect   print and check what an asset holds, with its energy per SH band\n"
    "  bench     time the transfer stage against a bare Embree occlusion loop\n"
    "  compare   uniform against adaptive refinement: tables, plots and relit frames\n"
    "  eval      surface RMS transfer error of an asset against a high-ray reference;\n"
    "            eval --fits INPUT: point, average and least-squares values on one mesh\n"
    "  render    relight an asset into a frame (Gouraud, or the per-pixel reference)\n"
    "  diff      compare two frames: relative RMSE, PSNR and an error heat map\n"
    "  view      write a self-contained HTML page that relights an asset in the browser\n"
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
    if (command == "merge") return cmd_merge(argc, argv);
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
    if (command == "view") return cmd_view(argc, argv);
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
