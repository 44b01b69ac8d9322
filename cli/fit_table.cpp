// Kavan et al. 2011, Table 1, on our scenes: point sampling, the hat-weighted average, the
// plain least-squares optimum (α = 0) and the regularised fit E(α), all from one set of vertex
// rays and one set of surface samples, judged by one reference (the eval command's seeded
// points, 8× the rays), beside the ray-casting time and each solve's time and memory.
// The paper's error is ∫(f − g)² over the area; ours is the RMS of ‖f − g‖ relative to
// ‖t_unshadowed‖ (for AO: in units of AO), at points traced independently of the samples.
#include "cli/fit_table.h"

#include <chrono>
#include <cstdio>

#include "cli/args.h"
#include "cli/bake_options.h"
#include "cli/pipeline.h"
#include "cli/report.h"
#include "prt/evaluate.h"
#include "prt/ray_scene.h"
#include "prt/sh.h"

namespace prtsub {

int cmd_eval_fits(int argc, char** argv) {
  std::string input, report;
  bool fits = false;
  BakeSettings b;
  ReferenceOptions ro;
  int points = static_cast<int>(ro.points), ref_rays = 0;
  double crease = 60;
  ArgParser args("eval --fits",
                 "The least-squares fit against its baselines on one mesh (Kavan et al. 2011, Table 1): E_point,\n"
                 "E_avg, E_lsq (alpha 0) and E(alpha), from the same vertex rays and surface samples, each judged\n"
                 "against the eval reference, with ray-casting time and each solve's time and memory.");
  args.flag("--fits", "this mode: INPUT is a mesh, not an asset", &fits);
  args.positional("INPUT", "mesh file", &input);
  args.option("--order", "N", "SH order (transfer)", &b.transfer.order, 1, kMaxShOrder);
  args.option("--rays", "R", "rays per vertex for point sampling", &b.transfer.rays, 1, 1 << 20);
  args.option("--seed", "S", "random seed", &b.transfer.seed);
  args.option("--threads", "T", "worker threads, 0 for every core", &b.transfer.threads, 0, 1024);
  args.option("--crease-angle", "DEG", "computed normals' crease angle", &crease, 0.0, 180.0);
  args.option("--points", "N", "reference points", &points, 1, 10000000);
  args.option("--reference-rays", "R", "reference rays per point (0: 8x the larger of --rays and --sample-rays)", &ref_rays, 0, 1 << 20);
  args.option("--report", "R.json", "also write a flat JSON report", &report);
  FitCli fit;
  fit.add(args);
  if (!args.parse(argc, argv, 2)) return 0;
  if (!report.empty()) check_writable(report);
  b.input = input;
  b.load = LoadOptions{crease};
  fit.apply(b);
  const bool ao = b.signal == AssetSignal::Ao;
  const FitOptions requested = b.fit;

  StageProgress progress;
  BakeSettings point_only = b;
  point_only.fit.method = FitMethod::Point;
  BakeResult base = run_bake(point_only, progress.callbacks());
  const Mesh& mesh = base.mesh;
  RayScene scene(mesh.positions, position_triangles(mesh));
  FitData data = sample_signal(mesh, scene, b, progress.callbacks());
  progress.finish();

  struct Column {
    std::string name;
    FitOptions options;
    RowMatrixXd values;
    FitStats stats;
    EvalResult error;
  };
  std::vector<Column> columns(4);
  columns[0].name = "point", columns[0].options.method = FitMethod::Point;
  columns[1].name = "avg", columns[1].options.method = FitMethod::Average;
  columns[2].name = "lsq", columns[2].options = requested, columns[2].options.method = FitMethod::LeastSquares, columns[2].options.alpha = 0;
  columns[3].name = "alpha", columns[3].options = requested, columns[3].options.method = FitMethod::LeastSquares;
  size_t clamped = 0;
  for (Column& c : columns) {
    c.values = fit_vertex_values(mesh, data.samples, data.moments, base.transfer, c.options, &c.stats);
    if (ao) {
      const size_t n = clamp_ao(c.values);
      if (&c == &columns[3]) clamped = n;
    }
  }

  auto t = std::chrono::steady_clock::now();
  ro.points = static_cast<size_t>(points);
  ro.rays = ref_rays > 0 ? ref_rays : 8 * std::max(b.transfer.rays, b.sample_rays);
  ro.order = b.transfer.order;
  ro.threads = b.transfer.threads;
  // The bake did not refine: its mesh and scene are the source's.
  Reference ref = make_reference(mesh, scene, ro);
  const double seconds_reference = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  for (Column& c : columns) c.error = evaluate(ref, vertex_positions(mesh), mesh.triangles, mesh.source_face, c.values);

  const char* unit = ao ? "of AO" : "of ||t_unshadowed||";
  std::printf("prtsub eval --fits: %s (%zu triangles, %zu vertices), %s\n", input.c_str(), mesh.num_faces(), mesh.num_vertices(),
              ao ? "ambient occlusion" : ("order " + std::to_string(b.transfer.order) + " transfer").c_str());
  std::printf("  rays:       vertices %d each (%.2f s); %zu surface samples, %d rays each (%.2f s)\n", b.transfer.rays,
              base.seconds_transfer, data.samples.size(), b.sample_rays, data.seconds);
  std::printf("  reference:  %zu points, %d rays each (%.2f s); its own noise floor %.3f%%\n", ref.source_face.size(), ref.rays,
              seconds_reference, 100 * ref.noise_floor);
  std::printf("  %-22s %9s %9s %10s %10s\n", "values", "RMS %", "p95 %", "solve s", "solve MiB");
  for (const Column& c : columns) {
    std::string label = c.name == "point" ? "E_point" : c.name == "avg" ? "E_avg" : c.name == "lsq" ? "E_lsq (alpha 0)" : "E(alpha " + std::to_string(requested.alpha).substr(0, 5) + ")";
    const double solve = c.stats.seconds_assemble + c.stats.seconds_factor + c.stats.seconds_solve;
    std::printf("  %-22s %9.3f %9.3f %10.3f %10.1f%s\n", label.c_str(), c.error.rms_percent, c.error.p95_percent, solve,
                c.stats.solve_memory_mib, c.stats.stabilizer > 0 ? "  (stabilised)" : "");
  }
  std::printf("  (errors in percent %s; lsq columns: %s regulariser, %s mass matrix%s)\n", unit,
              regularizer_name(requested.regularizer), mass_matrix_name(requested.mass),
              ao ? ("; " + std::to_string(clamped) + " values clamped").c_str() : "");
  for (const Column& c : columns)
    if (!c.stats.warning.empty()) std::fprintf(stderr, "prtsub: warning: %s\n", c.stats.warning.c_str());

  if (!report.empty()) {
    Report r;
    r.set("command", "eval --fits");
    r.set("input", input);
    r.set("signal", ao ? "ao" : "transfer");
    r.set("order", b.transfer.order);
    r.set("triangles", static_cast<uint64_t>(mesh.num_faces()));
    r.set("vertices", static_cast<uint64_t>(mesh.num_vertices()));
    r.set("rays_per_vertex", b.transfer.rays);
    r.set("samples", static_cast<uint64_t>(data.samples.size()));
    r.set("sample_rays", b.sample_rays);
    r.set("alpha", requested.alpha);
    r.set("regularizer", regularizer_name(requested.regularizer));
    r.set("mass", mass_matrix_name(requested.mass));
    r.set("seconds_rays_vertices", base.seconds_transfer);
    r.set("seconds_rays_samples", data.seconds);
    r.set("reference_points", static_cast<uint64_t>(ref.source_face.size()));
    r.set("reference_rays", ref.rays);
    r.set("noise_floor_percent", 100 * ref.noise_floor);
    if (ao) r.set("clamped_values", static_cast<uint64_t>(clamped));
    for (const Column& c : columns) {
      r.set("e_" + c.name + "_percent", c.error.rms_percent);
      r.set("p95_" + c.name + "_percent", c.error.p95_percent);
      r.set("seconds_solve_" + c.name, c.stats.seconds_assemble + c.stats.seconds_factor + c.stats.seconds_solve);
      r.set("solve_memory_mib_" + c.name, c.stats.solve_memory_mib);
      r.set("stabilizer_" + c.name, c.stats.stabilizer);
    }
    r.set("peak_memory_mib", peak_memory_mib());
    r.write(report);
  }
  return 0;
}

}  // namespace prtsub
