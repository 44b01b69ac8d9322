// Kavan et al. 2011, Table 1, on our scenes: point sampling, the hat-weighted average, the
// plain least-squares optimum (α = 0) and the regularised fit E(α), all from one set of vertex
// rays and one set of surface samples, judged by one reference (the eval command's seeded
// points, 8× the rays), beside the ray-casting time and each solve's time and memory.
// The paper's error is ∫(f − g)² over the area; ours is the RMS of ‖f − g‖ relative to
// ‖t_unshadowed‖ (for AO: in units of AO), at points traced independently of the samples.
#include <cstdio>

#include "cli/commands.h"
#include "cli/options.h"
#include "cli/report.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

struct Column {
  std::string name, label;
  FitOptions options;
  RowMatrixXd values;
  FitStats stats;
  EvalResult error;
};

// The paper's four columns use its plain estimators, E(α) at its recommended α = 0.1; "default"
// is the requested options as the bake runs them (noise weighting, the non-negative limit and the
// unshadowed part's exact projection).
std::vector<Column> fit_columns(const FitOptions& requested) {
  FitOptions plain = requested;
  plain.weigh_by_noise = false, plain.non_negative = NonNegative::Off, plain.unshadowed_order = 0;
  std::vector<Column> columns(5);
  columns[0].name = "point", columns[0].label = "E_point", columns[0].options.method = FitMethod::Point;
  columns[1].name = "avg", columns[1].label = "E_avg", columns[1].options.method = FitMethod::Average;
  columns[2].name = "lsq", columns[2].label = "E_lsq (alpha 0)", columns[2].options = plain;
  columns[2].options.method = FitMethod::LeastSquares, columns[2].options.alpha = 0;
  columns[3].name = "alpha", columns[3].label = "E(alpha 0.1)", columns[3].options = plain;
  columns[3].options.method = FitMethod::LeastSquares, columns[3].options.alpha = 0.1;
  char label[48];
  std::snprintf(label, sizeof label, "E_default (alpha %g)", requested.alpha);
  columns[4].name = "default", columns[4].label = label, columns[4].options = requested;
  return columns;
}

void print_table(const Report& r, const std::vector<Column>& columns, bool ao) {
  r.print(stdout, {"prtsub eval --fits: {input} ({triangles} triangles, {vertices} vertices), {signal_text}",
                   "  rays:       vertices {rays_per_vertex} each ({seconds_rays_vertices:2} s); {samples} surface samples, "
                   "{sample_rays} rays each ({seconds_rays_samples:2} s, pilot included)",
                   "  samples:    {sample_allocation} allocation; {sampled_faces} of {triangles} faces sampled; {pilot_samples} pilot "
                   "samples ({seconds_pilot:2} s)",
                   "  reference:  {reference_points} points, {reference_rays} rays each ({seconds_reference:2} s); its own noise "
                   "floor {noise_floor_percent:3}%"});
  std::printf("  %-22s %9s %9s %10s %10s\n", "values", "RMS %", "p95 %", "solve s", "solve MiB");
  for (const Column& c : columns)
    std::printf("  %-22s %9s %9s %10s %10s%s\n", c.label.c_str(), r.format("{e_" + c.name + "_percent:3}").c_str(),
                r.format("{p95_" + c.name + "_percent:3}").c_str(), r.format("{seconds_solve_" + c.name + ":3}").c_str(),
                r.format("{solve_memory_mib_" + c.name + ":1}").c_str(), c.stats.stabilizer > 0 ? "  (stabilised)" : "");
  r.print(stdout, {"  (default: {kept_correction:%1} of the fit's correction kept on average; {limited_vertices} vertices limited "
                   "to non-negative transfer)"});
  r.print(stdout, {ao ? "  (errors in percent of AO; lsq columns: {regularizer} regulariser, {mass} mass matrix; {clamped_values} "
                        "values clamped)"
                      : "  (errors in percent of ||t_unshadowed||; lsq columns: {regularizer} regulariser, {mass} mass matrix)"});
}

}  // namespace

int cmd_eval_fits(int argc, char** argv) {
  BakeCli cli;
  bool fits = false;
  ReferenceOptions ro;
  int ref_rays = 0;
  ArgParser args("eval --fits",
                 "The least-squares fit against its baselines on one mesh (Kavan et al. 2011, Table 1): E_point,\n"
                 "E_avg, E_lsq (alpha 0) and E(alpha), from the same vertex rays and surface samples, each judged\n"
                 "against the eval reference, with ray-casting time and each solve's time and memory.");
  args.flag("--fits", "this mode: INPUT is a mesh, not an asset", &fits);
  cli.add_common(args);
  args.option("--points", "N", "reference points", &ro.points, size_t(1), size_t(10000000));
  args.option("--reference-rays", "R", "reference rays per point (0: 8x the larger of --rays and --sample-rays)", &ref_rays, 0, 1 << 20);
  cli.add_fit(args);
  if (!args.parse(argc, argv, 2)) return 0;
  if (!cli.report.empty()) check_writable(cli.report);
  const BakeOptions b = resolve_bake_options(cli.options());
  require_fixed_order(b, "eval --fits");
  const bool ao = b.signal == AssetSignal::Ao;
  if (b.bounce.bounces > 0 || b.bounce.until_converged) throw UsageError("eval --fits: compares fits of direct transfer; --bounces does not apply");

  // One bake for the vertices' rays, one set of samples; every column is fitted from them.
  StageProgress progress;
  BakeOptions point_only = b;
  point_only.fit.method = FitMethod::Point;
  const BakeResult base = bake(load_mesh(cli.input, cli.load), point_only, progress.callbacks());
  const Mesh& mesh = base.mesh;
  const RayScene scene(mesh.positions, position_triangles(mesh));
  const FitData data = sample_signal(mesh, scene, b, &base.transfer, &base.point_variance, progress.callbacks());
  progress.finish();
  std::vector<Column> columns = fit_columns(b.fit);
  size_t clamped = 0;
  for (Column& c : columns) {
    if (&c == &columns.back()) {  // the default: as the bake fits, α chosen on the hold-out when auto
      double alpha = 0;
      std::vector<std::pair<double, double>> trials;
      c.values = fit_bake_values(mesh, data, base.transfer, base.point_variance, b, &c.stats, &alpha, &trials);
      if (!trials.empty()) {
        char label[64];
        std::snprintf(label, sizeof label, "E_default (alpha auto: %g)", alpha);
        c.label = label;
      }
    } else {
      c.values = fit_vertex_values(mesh, data.samples, data.moments, base.transfer, c.options, &c.stats, &base.point_variance);
    }
    if (ao) {
      const size_t n = clamp_ao(c.values);
      if (&c == &columns.back()) clamped = n;
    }
  }

  Stopwatch clock;
  ro.rays = ref_rays > 0 ? ref_rays : 8 * std::max(b.transfer.rays, b.sample_rays);
  ro.order = b.transfer.order;
  ro.threads = b.transfer.threads;
  const Reference ref = make_reference(mesh, scene, ro);  // the bake did not refine: its mesh is the source
  const double seconds_reference = clock.lap();
  for (Column& c : columns) c.error = evaluate(ref, vertex_positions(mesh), mesh.triangles, mesh.source_face, c.values);

  Report r;
  r.set("command", "eval --fits");
  r.set("input", cli.input);
  r.set("signal", ao ? "ao" : "transfer");
  r.set("signal_text", ao ? "ambient occlusion" : "order " + std::to_string(b.transfer.order) + " transfer");
  r.set("order", b.transfer.order);
  r.set("triangles", mesh.num_faces());
  r.set("vertices", mesh.num_vertices());
  r.set("rays_per_vertex", b.transfer.rays);
  r.set("samples", data.samples.size());
  r.set("sample_rays", data.sample_rays);
  r.set("sample_allocation", sample_allocation_name(data.allocation));
  r.set("pilot_samples", data.plan.pilot_samples);
  r.set("sampled_faces", data.allocation == SampleAllocation::Pilot ? data.plan.sampled_faces : mesh.num_faces());
  r.set("seconds_pilot", data.plan.seconds);
  r.set("alpha", b.fit.alpha);
  r.set("regularizer", regularizer_name(b.fit.regularizer));
  r.set("mass", mass_matrix_name(b.fit.mass));
  r.set("seconds_rays_vertices", base.seconds_transfer);
  r.set("seconds_rays_samples", data.seconds);
  r.set("reference_points", ref.source_face.size());
  r.set("reference_rays", ref.rays);
  r.set("seconds_reference", seconds_reference);
  r.set("noise_floor_percent", 100 * ref.noise_floor);
  if (ao) r.set("clamped_values", clamped);
  for (const Column& c : columns) {
    r.set("e_" + c.name + "_percent", c.error.rms_percent);
    r.set("p95_" + c.name + "_percent", c.error.p95_percent);
    r.set("seconds_solve_" + c.name, c.stats.seconds_assemble + c.stats.seconds_factor + c.stats.seconds_solve);
    r.set("solve_memory_mib_" + c.name, c.stats.solve_memory_mib);
    r.set("stabilizer_" + c.name, c.stats.stabilizer);
  }
  r.set("kept_correction", columns.back().stats.kept_correction);
  r.set("limited_vertices", columns.back().stats.limited_vertices);
  r.set("peak_memory_mib", peak_memory_mib());
  print_table(r, columns, ao);
  for (const Column& c : columns)
    if (!c.stats.warning.empty()) std::fprintf(stderr, "prtsub: warning: %s\n", c.stats.warning.c_str());
  if (!cli.report.empty()) r.write(cli.report);
  return 0;
}

}  // namespace prtsub
