// bench: the transfer stage against a bare Embree occlusion loop over the same rays, in the same
// run, alternating (the machine is shared and noisy; ratios are what hold); or the fit's solve.
#include <cmath>
#include <cstdio>

#include "cli/commands.h"
#include "cli/options.h"
#include "cli/report.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/interreflection.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

// bench --solve: the fit's cost alone, best of `repeat` runs, on pseudo-random face moments.
Report bench_solve(const Mesh& mesh, const BakeOptions& b, int repeat) {
  Stopwatch clock;
  const SurfaceSamples samples = make_surface_samples(mesh, b.samples);
  const double t_samples = clock.lap();
  const Eigen::Index K = sh_count(b.transfer.order);
  // The bake reduces the samples' transfer to face moments while tracing (bench --at samples
  // times that); the fit starts from the moments.
  FaceMoments moments{RowMatrixXd(static_cast<Eigen::Index>(3 * mesh.num_faces()), K), {}};
  RowMatrixXd prior(static_cast<Eigen::Index>(mesh.num_vertices()), K);
  Rng rng(b.transfer.seed, 0);
  for (Eigen::Index i = 0; i < moments.rows.size(); ++i) moments.rows.data()[i] = rng.uniform();
  for (Eigen::Index i = 0; i < prior.size(); ++i) prior.data()[i] = rng.uniform();
  FitOptions o = b.fit;
  o.method = FitMethod::LeastSquares;
  o.threads = b.transfer.threads;
  FitStats best;
  double best_total = INFINITY;
  for (int i = 0; i < repeat; ++i) {
    FitStats st;
    fit_vertex_values(mesh, samples, moments, prior, o, &st);
    const double total = st.seconds_assemble + st.seconds_factor + st.seconds_solve;
    std::printf("  run %d: %.3f s (assemble %.3f, factor %.3f, solve %.3f; %s, %d CG iterations)\n", i + 1, total,
                st.seconds_assemble, st.seconds_factor, st.seconds_solve, st.solver.c_str(), st.cg_iterations);
    if (total < best_total) best_total = total, best = st;
  }
  Report r;
  r.set("command", "bench --solve");
  r.set("vertices", mesh.num_vertices());
  r.set("samples", samples.size());
  r.set("right_hand_sides", static_cast<int64_t>(K));
  r.set("alpha", o.alpha);
  r.set("regularizer", regularizer_name(o.regularizer));
  r.set("mass", mass_matrix_name(o.mass));
  r.set("seconds_samples", t_samples);
  r.set("seconds_fit_best", best_total);
  r.set("seconds_fit_assemble", best.seconds_assemble);
  r.set("seconds_fit_assemble_sums", best.seconds_assemble_sums);
  r.set("seconds_fit_assemble_edges", best.seconds_assemble_edges);
  r.set("seconds_fit_assemble_rows", best.seconds_assemble_rows);
  r.set("seconds_fit_factor", best.seconds_factor);
  r.set("seconds_fit_solve", best.seconds_solve);
  r.set("fit_solver", best.solver);
  r.set("fit_cg_iterations", best.cg_iterations);
  r.set("fit_multigrid_levels", best.multigrid_levels);
  r.set("fit_multigrid_operator_complexity", best.multigrid_operator_complexity);
  r.set("fit_system_nonzeros", best.system_nonzeros);
  r.set("fit_factor_nonzeros", best.factor_nonzeros);
  r.set("fit_stiff_share", best.stiff_share);
  r.set("fit_stiff_rows", best.stiff_rows);
  r.set("fit_stiff_factor_nonzeros", best.stiff_factor_entries);
  r.set("solve_memory_mib", best.solve_memory_mib);
  r.print(stdout, {"  best:       {seconds_fit_best:3} s; system {fit_system_nonzeros} non-zeros, factor {fit_factor_nonzeros} "
                   "entries, {solve_memory_mib:1} MiB; {fit_stiff_share:3} of the rows stiff, "
                   "{fit_stiff_rows} solved directly in CG (factor {fit_stiff_factor_nonzeros} entries)"});
  return r;
}

// The transfer stage as the bake runs it, at the vertices or at the fit's samples (where each
// face's transfer is reduced to the fit's moments as it is traced), against the bare loop.
Report bench_transfer(const Mesh& mesh, const BakeOptions& b, bool at_samples, int repeat) {
  Stopwatch clock;
  const RayScene scene(mesh.positions, position_triangles(mesh));
  const double t_scene = clock.lap();
  SurfaceSamples samples;
  RowMatrixX3d vertex_points, vertex_normals, vertex_offsets;
  if (at_samples) samples = make_surface_samples(mesh, b.samples);
  else vertex_points = vertex_positions(mesh), vertex_normals = mesh.normals, vertex_offsets = vertex_offset_directions(mesh);
  const RowMatrixX3d& points = at_samples ? samples.points : vertex_points;
  const RowMatrixX3d& normals = at_samples ? samples.normals : vertex_normals;
  const RowMatrixX3d& offsets = at_samples ? samples.offsets : vertex_offsets;
  double best_transfer = INFINITY, best_bare = INFINITY;
  uint64_t rays = 0, occluded = 0;
  std::printf("  %lld %s, order %d, %d rays each\n", static_cast<long long>(points.rows()), at_samples ? "surface samples" : "vertices",
              b.transfer.order, b.transfer.rays);
  for (int i = 0; i < repeat; ++i) {
    TransferStats bare, full;
    occluded = bare_occlusion_loop(scene, points, normals, b.transfer, &bare, &offsets);
    if (at_samples) trace_face_moments(mesh, scene, samples, b.transfer, &full);
    else shadowed_transfer(scene, points, normals, b.transfer, &full, {}, &offsets);
    rays = full.rays;
    best_bare = std::min(best_bare, bare.seconds);
    best_transfer = std::min(best_transfer, full.seconds);
    std::printf("  run %d: bare %.3f s, transfer %.3f s\n", i + 1, bare.seconds, full.seconds);
  }
  const double bare_rps = static_cast<double>(rays) / best_bare, transfer_rps = static_cast<double>(rays) / best_transfer;
  Report r;
  r.set("command", "bench");
  r.set("order", b.transfer.order);
  r.set("rays_per_vertex", b.transfer.rays);
  r.set("threads", b.transfer.threads);
  r.set("vertices", mesh.num_vertices());
  r.set("triangles", mesh.num_faces());
  r.set("at", at_samples ? "samples" : "vertices");
  r.set("points", static_cast<uint64_t>(points.rows()));
  r.set("rays", rays);
  r.set("repeat", repeat);
  r.set("occluded_fraction", static_cast<double>(occluded) / static_cast<double>(rays));
  r.set("transfer_rays_per_second", transfer_rps);
  r.set("bare_rays_per_second", bare_rps);
  r.set("transfer_over_bare", transfer_rps / bare_rps);
  r.set("seconds_scene", t_scene);
  r.set("seconds_transfer_best", best_transfer);
  r.set("seconds_bare_best", best_bare);
  r.set("bare_mrays", bare_rps / 1e6);
  r.set("transfer_mrays", transfer_rps / 1e6);
  r.print(stdout, {"  bare loop:  {bare_mrays:2} Mrays/s", "  transfer:   {transfer_mrays:2} Mrays/s ({transfer_over_bare:%1} of bare)",
                   "  occluded:   {occluded_fraction:%1} of rays; scene build {seconds_scene:3} s"});
  return r;
}

// One bounce pass as the bake runs it without the cache (closest hits, then the previous pass
// interpolated at each), against the bare closest-hit loop over the same rays; and the direct
// stage's bare occlusion loop from the same vertices, for what a pass costs against a direct one.
Report bench_bounce(const Mesh& mesh, const BakeOptions& b, int repeat) {
  Stopwatch clock;
  const RayScene scene(mesh.positions, position_triangles(mesh));
  const double t_scene = clock.lap();
  BounceOptions o = b.bounce;
  o.bounces = 1, o.until_converged = false, o.cache = BounceCache::Off;
  o.rays = b.transfer.rays, o.seed = b.transfer.seed, o.threads = b.transfer.threads;
  const RowMatrixXd previous = RowMatrixXd::Zero(static_cast<Eigen::Index>(mesh.num_vertices()), sh_count(b.transfer.order));
  const RowMatrixX3d points = vertex_positions(mesh), offsets = vertex_offset_directions(mesh);
  double best_pass = INFINITY, best_bare = INFINITY, best_direct = INFINITY;
  uint64_t rays = 0, hits = 0;
  std::printf("  %zu vertices, order %d, %d rays each\n", mesh.num_vertices(), b.transfer.order, o.rays);
  for (int i = 0; i < repeat; ++i) {
    TransferStats bare, direct;
    BounceStats pass;
    hits = bare_bounce_loop(mesh, scene, o, &bare);
    interreflected_transfer(mesh, scene, previous, o, &pass);
    bare_occlusion_loop(scene, points, mesh.normals, b.transfer, &direct, &offsets);
    rays = bare.rays;
    best_bare = std::min(best_bare, bare.seconds), best_pass = std::min(best_pass, pass.seconds);
    best_direct = std::min(best_direct, direct.seconds);
    std::printf("  run %d: bare closest-hit %.3f s, bounce pass %.3f s, bare occlusion %.3f s\n", i + 1, bare.seconds, pass.seconds,
                direct.seconds);
  }
  Report r;
  r.set("command", "bench --at bounces");
  r.set("order", b.transfer.order);
  r.set("rays_per_vertex", o.rays);
  r.set("threads", b.transfer.threads);
  r.set("vertices", mesh.num_vertices());
  r.set("triangles", mesh.num_faces());
  r.set("at", "bounces");
  r.set("rays", rays);
  r.set("repeat", repeat);
  r.set("hit_fraction", static_cast<double>(hits) / static_cast<double>(rays));
  r.set("seconds_scene", t_scene);
  r.set("seconds_bounce_pass_best", best_pass);
  r.set("seconds_bare_best", best_bare);
  r.set("seconds_bare_occlusion_best", best_direct);
  r.set("bounce_mrays", static_cast<double>(rays) / best_pass / 1e6);
  r.set("bare_mrays", static_cast<double>(rays) / best_bare / 1e6);
  r.set("bare_occlusion_mrays", static_cast<double>(rays) / best_direct / 1e6);
  r.set("bounce_over_bare", best_bare / best_pass);
  r.set("bounce_over_occlusion", best_direct / best_pass);
  r.print(stdout, {"  bare loop:  {bare_mrays:2} Mrays/s (closest hit); {bare_occlusion_mrays:2} Mrays/s (occlusion, the direct stage's)",
                   "  bounce:     {bounce_mrays:2} Mrays/s ({bounce_over_bare:%1} of the closest-hit loop, {bounce_over_occlusion:%1} of "
                   "the occlusion loop)",
                   "  hits:       {hit_fraction:%1} of rays; scene build {seconds_scene:3} s"});
  return r;
}

}  // namespace

int cmd_bench(int argc, char** argv) {
  BakeCli cli;
  int repeat = 2;
  std::string at = "vertices";
  bool solve = false;
  ArgParser args("bench",
                 "Times the bake's transfer stage against a bare Embree occlusion loop casting the same rays\n"
                 "from the same points with the same threads, alternating runs; the best run of each counts.");
  cli.add_common(args);
  args.option("--repeat", "N", "runs of each, alternated", &repeat, 1, 100);
  args.option("--at", "vertices|samples|bounces", "trace from the vertices, or from the fit's surface samples, or time one\n"
              "bounce pass (interreflection) against a bare closest-hit loop [default vertices]", &at);
  args.flag("--solve", "instead, time the least-squares fit's assembly, factorisation and solve for order² right-hand\n"
            "sides (values need no rays: the cost does not depend on them)", &solve);
  cli.add_fit(args);
  if (!args.parse(argc, argv, 2)) return 0;
  if (at != "vertices" && at != "samples" && at != "bounces") throw UsageError("--at: unknown value '" + at + "' (vertices, samples, bounces)");
  const BakeOptions options = resolve_bake_options(cli.options());  // samples as bake() places them
  require_fixed_order(options, "bench");
  if (!cli.report.empty()) check_writable(cli.report);

  Stopwatch clock;
  const Mesh mesh = load_mesh(cli.input, cli.load);
  const double t_load = clock.lap();
  std::printf("prtsub bench%s: %s, %zu vertices\n", solve ? " --solve" : "", cli.input.c_str(), mesh.num_vertices());
  Report r = solve ? bench_solve(mesh, options, repeat)
             : at == "bounces" ? bench_bounce(mesh, options, repeat)
                               : bench_transfer(mesh, options, at == "samples", repeat);
  r.set("input", cli.input);
  r.set("seconds_load", t_load);
  r.set("peak_memory_mib", peak_memory_mib());
  r.print(stdout, {"  peak memory {peak_memory_mib:0} MiB"});
  if (!cli.report.empty()) r.write(cli.report);
  return 0;
}

}  // namespace prtsub
