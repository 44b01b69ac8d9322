// Command wiring: each command fills a settings struct from its options and runs the
// pipeline stages in order (mesh -> transfer -> asset), timing each stage for the summary
// and the JSON report.
#include "cli/commands.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string>

#include "cli/args.h"
#include "cli/bake_options.h"
#include "cli/progress.h"
#include "cli/report.h"
#include "cli/compare.h"
#include "cli/fit_table.h"
#include "cli/pipeline.h"
#include "prt/asset.h"
#include "prt/evaluate.h"
#include "prt/image_io.h"
#include "prt/lights.h"
#include "prt/render.h"
#include "prt/ray_scene.h"
#include "prt/sh.h"
#include "prt/sampling.h"
#include "prt/surface_samples.h"
#include "prt/transfer.h"
#include "subdiv/mesh_io.h"

namespace prtsub {
namespace {


class Stopwatch {
 public:
  double lap() {
    auto now = std::chrono::steady_clock::now();
    double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }
  double total() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_ = start_;
};

void add_defects(Report& r, const MeshDefects& d) {
  r.set("defects_degenerate_faces", static_cast<uint64_t>(d.degenerate_faces));
  r.set("defects_zero_area_faces", static_cast<uint64_t>(d.zero_area_faces));
  r.set("defects_duplicate_faces", static_cast<uint64_t>(d.duplicate_faces));
  r.set("defects_unreferenced_vertices", static_cast<uint64_t>(d.unreferenced_vertices));
  r.set("defects_winding_conflicts", static_cast<uint64_t>(d.winding_conflicts));
  r.set("defects_non_manifold_edges", static_cast<uint64_t>(d.non_manifold_edges));
  r.set("defects_invalid_file_normals", static_cast<uint64_t>(d.invalid_file_normals));
  r.set("defects_corners_without_uv", static_cast<uint64_t>(d.corners_without_uv));
  r.set("welded_vertices", static_cast<uint64_t>(d.welded_vertices));
  r.set("boundary_edges", static_cast<uint64_t>(d.boundary_edges));
  r.set("polygons_triangulated", static_cast<uint64_t>(d.polygons_triangulated));
}

void print_defects(const MeshDefects& d) {
  std::printf("  tolerated:  %zu degenerate faces dropped, %zu zero-area faces, %zu duplicate faces,\n"
              "              %zu unreferenced vertices dropped, %zu winding conflicts, %zu non-manifold edges,\n"
              "              %zu invalid file normals, %zu corners without UVs (0, 0)\n",
              d.degenerate_faces, d.zero_area_faces, d.duplicate_faces, d.unreferenced_vertices,
              d.winding_conflicts, d.non_manifold_edges, d.invalid_file_normals, d.corners_without_uv);
  std::printf("  topology:   %zu boundary edges, %zu vertices welded, %zu polygons triangulated\n",
              d.boundary_edges, d.welded_vertices, d.polygons_triangulated);
}

struct CommonOptions {
  std::string input;
  std::string report;
  TransferOptions transfer;
  double crease_angle = 60.0;
};

void add_common(ArgParser& args, CommonOptions& c) {
  args.positional("INPUT", "mesh file: .obj, .ply (ASCII or binary), .off or .stl", &c.input);
  args.option("--order", "N", "SH order: N bands, N² coefficients", &c.transfer.order, 1, kMaxShOrder);
  args.option("--rays", "R", "rays per vertex", &c.transfer.rays, 1, 1 << 20);
  args.option("--seed", "S", "random seed; results depend on it, not on threads", &c.transfer.seed);
  args.option("--threads", "T", "worker threads, 0 for every core", &c.transfer.threads, 0, 1024);
  args.option("--crease-angle", "DEG", "computed normals: sharper edges are creases; 0 is flat shading", &c.crease_angle, 0.0, 180.0);
  args.option("--report", "R.json", "also write a flat JSON report", &c.report);
}

// ", 31 CG iterations", or the iterations CG spent before CHOLMOD took over.
std::string cg_note(const FitStats& f) {
  if (f.cg_iterations == 0) return "";
  return ", " + std::to_string(f.cg_iterations) + (f.solver == "cg" ? " CG iterations" : " CG iterations first");
}

int cmd_bake(int argc, char** argv) {
  CommonOptions c;
  BakeSettings b;
  std::string output, estimate = "root", scheme = "linear";
  int budget = 0;
  ArgParser args("bake", "Computes shadowed SH transfer at every vertex and writes a PRT asset (binary PLY).\n"
                         "With --refine, first refines the mesh: adaptively to a triangle budget where the transfer\n"
                         "changes, or uniformly (OpenSubdiv) as a baseline.");
  add_common(args, c);
  args.option("--output", "ASSET.ply", "output asset (required)", &output);
  args.alias("-o", "--output");
  args.option("--refine", "none|adaptive|uniform", "refinement [default none]", &b.refine);
  args.option("--budget", "T", "adaptive: output triangle count", &budget, 0, 1 << 30);
  args.option("--estimate", "relative|shadow|curvature|length|probe|root", "adaptive: edge error estimate [default root]", &estimate);
  args.option("--max-edge", "L", "adaptive: first split edges longer than L (0: off)", &b.max_edge, 0.0, 1e30);
  int batch = 256;
  args.option("--batch", "B", "adaptive: faces split per Embree batch", &batch, 1, 1 << 20);
  args.option("--levels", "K", "uniform: 1→4 splits per face", &b.uniform.levels, 1, 8);
  args.option("--scheme", "linear|loop", "uniform: linear keeps the surface; loop smooths it [default linear]", &scheme);
  FitCli fit;
  fit.add(args);
  if (!args.parse(argc, argv, 2)) return 0;
  if (output.empty()) throw UsageError("bake: missing -o ASSET.ply");
  if (b.refine == "adaptive" && budget <= 0) throw UsageError("--budget: required with --refine adaptive");
  b.input = c.input;
  b.load = LoadOptions{c.crease_angle};
  b.transfer = c.transfer;
  b.budget = static_cast<size_t>(budget);
  b.batch = static_cast<size_t>(batch);
  b.estimate = parse_estimate(estimate);
  b.uniform.scheme = parse_uniform_scheme(scheme);
  b.uniform.crease_angle_deg = c.crease_angle;
  fit.apply(b);
  check_transfer_options(c.transfer);
  check_writable(output);
  if (!c.report.empty()) check_writable(c.report);

  StageProgress progress;
  BakeResult res = run_bake(b, progress.callbacks());
  progress.finish();
  auto t_write0 = std::chrono::steady_clock::now();
  write_asset(output, res.mesh, res.transfer, res.metadata, b.signal);
  const double t_write = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_write0).count();
  const double total = res.seconds_total + t_write;
  const double transfer_seconds = res.seconds_transfer + res.refine.seconds_signal + res.seconds_samples;
  const double rays_per_second = static_cast<double>(res.rays) / std::max(transfer_seconds, 1e-9);
  const Mesh& mesh = res.mesh;

  Report r;
  r.set("command", "bake");
  r.set("input", c.input);
  r.set("output", output);
  r.set("order", c.transfer.order);
  r.set("rays_per_vertex", c.transfer.rays);
  r.set("seed", c.transfer.seed);
  r.set("crease_angle", c.crease_angle);
  r.set("refine", b.refine);
  r.set("triangles_in", static_cast<uint64_t>(mesh.input_triangles));
  r.set("vertices_in", static_cast<uint64_t>(mesh.input_vertices));
  r.set("triangles_out", static_cast<uint64_t>(mesh.num_faces()));
  r.set("vertices_out", static_cast<uint64_t>(mesh.num_vertices()));
  r.set("positions_out", static_cast<uint64_t>(mesh.positions.rows()));
  r.set("normals_from_file", mesh.normals_from_file);
  r.set("rays", res.rays);
  r.set("rays_per_second", rays_per_second);
  r.set("seconds_total", total);
  r.set("seconds_load", res.seconds_load);
  r.set("seconds_scene", res.seconds_scene);
  r.set("seconds_transfer", res.seconds_transfer);
  r.set("seconds_refine", res.seconds_refine);
  r.set("seconds_write", t_write);
  r.set("peak_memory_mib", peak_memory_mib());
  if (b.refine == "adaptive") {
    const RefineStats& st = res.refine;
    r.set("budget", static_cast<uint64_t>(b.budget));
    r.set("estimate", estimate);
    r.set("batch", static_cast<uint64_t>(b.batch));
    r.set("max_edge", b.max_edge);
    r.set("splits", static_cast<uint64_t>(st.splits));
    r.set("pre_refinement_splits", static_cast<uint64_t>(st.pre_refinement_splits));
    r.set("boundary_splits", static_cast<uint64_t>(st.boundary_splits));
    r.set("new_vertices", static_cast<uint64_t>(st.new_vertices));
    r.set("batches", static_cast<uint64_t>(st.batches));
    r.set("non_manifold_edges_kept", static_cast<uint64_t>(st.non_manifold_edges_kept));
    r.set("min_angle_before_deg", st.min_angle_before_deg);
    r.set("min_angle_after_deg", st.min_angle_after_deg);
    r.set("seconds_refine_rays", st.seconds_signal);
    r.set("refine_overhead_fraction", st.seconds_total > 0 ? (st.seconds_total - st.seconds_signal) / st.seconds_total : 0.0);
  }
  if (b.refine == "uniform") r.set("levels", b.uniform.levels), r.set("scheme", scheme);
  add_fit_report(r, res, b);
  if (b.signal == AssetSignal::Ao) r.set("clamped_values", static_cast<uint64_t>(res.clamped));
  r.set("warnings", static_cast<uint64_t>(res.warnings.size()));
  add_defects(r, mesh.defects);

  std::printf("prtsub bake: %s -> %s\n", c.input.c_str(), output.c_str());
  std::printf("  input:      %zu triangles, %zu vertices\n", mesh.input_triangles, mesh.input_vertices);
  std::printf("  output:     %zu triangles, %zu vertices (%lld positions; normals %s%s)\n", mesh.num_faces(),
              mesh.num_vertices(), static_cast<long long>(mesh.positions.rows()),
              mesh.normals_from_file ? "from file" : "computed", mesh.has_uv() ? "; UVs from file" : "");
  print_defects(mesh.defects);
  if (b.refine == "adaptive") {
    const RefineStats& st = res.refine;
    std::printf("  refine:     adaptive, estimate %s, %zu splits (%zu boundary, %zu pre-refinement) in %zu batches\n",
                estimate.c_str(), st.splits, st.boundary_splits, st.pre_refinement_splits, st.batches);
    std::printf("              min angle %.3f° before, %.3f° after; %zu non-manifold edges never split\n",
                st.min_angle_before_deg, st.min_angle_after_deg, st.non_manifold_edges_kept);
    std::printf("              %.3f s, of which %.3f s tracing new vertices (overhead %.1f%%)\n", st.seconds_total,
                st.seconds_signal, st.seconds_total > 0 ? 100 * (st.seconds_total - st.seconds_signal) / st.seconds_total : 0.0);
  }
  if (b.refine == "uniform")
    std::printf("  refine:     uniform (OpenSubdiv, %s), %d levels, %.3f s\n", scheme.c_str(), b.uniform.levels, res.seconds_refine);
  if (b.signal == AssetSignal::Ao)
    std::printf("  signal:     ambient occlusion, %d rays per vertex, seed %llu; %zu values clamped into [0, 1]\n",
                c.transfer.rays, static_cast<unsigned long long>(c.transfer.seed), res.clamped);
  else
    std::printf("  transfer:   order %d (%d coefficients), %d rays per vertex, seed %llu\n", c.transfer.order,
                sh_count(c.transfer.order), c.transfer.rays, static_cast<unsigned long long>(c.transfer.seed));
  if (b.fit.method == FitMethod::Average)
    std::printf("  fit:        average of %zu surface samples (%d rays each) in %.3f s\n", res.fit_data.samples.size(),
                b.sample_rays, res.seconds_samples + res.seconds_fit);
  if (b.fit.method == FitMethod::LeastSquares) {
    const FitStats& f = res.fit;
    std::printf("  fit:        least squares, %s regulariser, alpha %g, %s mass; %zu surface samples (%d rays each, %.3f s)\n",
                regularizer_name(b.fit.regularizer), b.fit.alpha, mass_matrix_name(b.fit.mass), res.fit_data.samples.size(),
                b.sample_rays, res.seconds_samples);
    std::printf("              solve %.3f s (assemble %.3f, factor %.3f, solve %.3f; %s%s), %.1f MiB; %zu vertices unsupported\n",
                res.seconds_fit, f.seconds_assemble, f.seconds_factor, f.seconds_solve, f.solver.c_str(),
                cg_note(f).c_str(), f.solve_memory_mib, f.unsupported);
  }
  std::printf("  rays:       %llu in %.3f s (%.2f Mrays/s)\n", static_cast<unsigned long long>(res.rays), transfer_seconds,
              rays_per_second / 1e6);
  std::printf("  time:       %.3f s total (load %.3f, scene %.3f, transfer %.3f, refine %.3f, samples %.3f, fit %.3f, write %.3f);\n"
              "              peak memory %.0f MiB\n",
              total, res.seconds_load, res.seconds_scene, res.seconds_transfer, res.seconds_refine, res.seconds_samples,
              res.seconds_fit, t_write, peak_memory_mib());
  for (const std::string& w : res.warnings) std::fprintf(stderr, "prtsub: warning: %s\n", w.c_str());
  if (!c.report.empty()) r.write(c.report);
  return 0;
}

int cmd_inspect(int argc, char** argv) {
  std::string input, report;
  ArgParser args("inspect", "Prints what a PRT asset holds, checks it, and shows the transfer's energy per SH band.");
  args.positional("ASSET", "a .ply asset written by prtsub bake", &input);
  args.option("--report", "R.json", "also write a flat JSON report", &report);
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

// bench --solve: the fit's cost alone, best of `repeat` runs, on pseudo-random face moments.
int bench_solve(const CommonOptions& c, const Mesh& mesh, const BakeSettings& b, int repeat) {
  Stopwatch clock;
  SurfaceSamples samples = make_surface_samples(mesh, b.samples);
  const double t_samples = clock.lap();
  const Eigen::Index K = sh_count(c.transfer.order);
  // The bake reduces the samples' transfer to face moments while tracing (bench --at samples
  // times that); the fit starts from the moments.
  FaceMoments moments{RowMatrixXd(static_cast<Eigen::Index>(3 * mesh.num_faces()), K)};
  RowMatrixXd prior(static_cast<Eigen::Index>(mesh.num_vertices()), K);
  Rng rng(c.transfer.seed, 0);
  for (Eigen::Index i = 0; i < moments.rows.size(); ++i) moments.rows.data()[i] = rng.uniform();
  for (Eigen::Index i = 0; i < prior.size(); ++i) prior.data()[i] = rng.uniform();
  FitOptions o = b.fit;
  o.method = FitMethod::LeastSquares;
  FitStats best;
  double best_total = INFINITY;
  std::printf("prtsub bench --solve: %s, %zu vertices, %zu samples, %lld right-hand sides, %s regulariser, alpha %g, %s mass\n",
              c.input.c_str(), mesh.num_vertices(), samples.size(), static_cast<long long>(K), regularizer_name(o.regularizer),
              o.alpha, mass_matrix_name(o.mass));
  for (int i = 0; i < repeat; ++i) {
    FitStats st;
    fit_vertex_values(mesh, samples, moments, prior, o, &st);
    const double total = st.seconds_assemble + st.seconds_factor + st.seconds_solve;
    std::printf("  run %d: %.3f s (assemble %.3f, factor %.3f, solve %.3f; %s%s)\n", i + 1, total, st.seconds_assemble,
                st.seconds_factor, st.seconds_solve, st.solver.c_str(), cg_note(st).c_str());
    if (total < best_total) best_total = total, best = st;
  }
  std::printf("  best:       %.3f s; system %zu non-zeros, factor %zu entries, %.1f MiB; peak memory %.0f MiB\n", best_total,
              best.system_nonzeros, best.factor_nonzeros, best.solve_memory_mib, peak_memory_mib());
  if (!c.report.empty()) {
    Report r;
    r.set("command", "bench --solve");
    r.set("input", c.input);
    r.set("vertices", static_cast<uint64_t>(mesh.num_vertices()));
    r.set("samples", static_cast<uint64_t>(samples.size()));
    r.set("right_hand_sides", static_cast<int64_t>(K));
    r.set("alpha", o.alpha);
    r.set("regularizer", regularizer_name(o.regularizer));
    r.set("mass", mass_matrix_name(o.mass));
    r.set("seconds_samples", t_samples);
    r.set("seconds_fit_best", best_total);
    r.set("seconds_fit_assemble", best.seconds_assemble);
    r.set("seconds_fit_factor", best.seconds_factor);
    r.set("seconds_fit_solve", best.seconds_solve);
    r.set("fit_solver", best.solver);
    r.set("fit_cg_iterations", best.cg_iterations);
    r.set("fit_system_nonzeros", static_cast<uint64_t>(best.system_nonzeros));
    r.set("fit_factor_nonzeros", static_cast<uint64_t>(best.factor_nonzeros));
    r.set("solve_memory_mib", best.solve_memory_mib);
    r.set("peak_memory_mib", peak_memory_mib());
    r.write(c.report);
  }
  return 0;
}

int cmd_bench(int argc, char** argv) {
  CommonOptions c;
  int repeat = 2;
  ArgParser args("bench",
                 "Times the bake's transfer stage against a bare Embree occlusion loop casting the same rays\n"
                 "from the same points with the same threads, alternating runs; the best run of each counts.");
  add_common(args, c);
  args.option("--repeat", "N", "runs of each, alternated", &repeat, 1, 100);
  std::string at = "vertices";
  args.option("--at", "vertices|samples", "trace from the vertices, or from the fit's surface samples [default vertices]", &at);
  bool solve = false;
  args.flag("--solve", "instead, time the least-squares fit's assembly, factorisation and solve for order² right-hand\n"
            "sides (values need no rays: the cost does not depend on them)", &solve);
  FitCli fit;
  fit.add(args);
  if (!args.parse(argc, argv, 2)) return 0;
  if (at != "vertices" && at != "samples") throw UsageError("--at must be vertices or samples, got '" + at + "'");
  check_transfer_options(c.transfer);
  if (!c.report.empty()) check_writable(c.report);
  BakeSettings settings;
  settings.transfer = c.transfer;
  fit.apply(settings);

  Stopwatch clock;
  Mesh mesh = load_mesh(c.input, LoadOptions{c.crease_angle});
  const double t_load = clock.lap();
  if (solve) return bench_solve(c, mesh, settings, repeat);
  RayScene scene(mesh.positions, position_triangles(mesh));
  const double t_scene = clock.lap();
  SurfaceSamples samples;
  RowMatrixX3d vertex_points, vertex_normals, vertex_offsets;
  if (at == "samples") {
    samples = make_surface_samples(mesh, settings.samples);
  } else {
    vertex_points = vertex_positions(mesh), vertex_normals = mesh.normals, vertex_offsets = vertex_offset_directions(mesh);
  }
  const bool at_samples = at == "samples";
  const RowMatrixX3d& points = at_samples ? samples.points : vertex_points;
  const RowMatrixX3d& normals = at_samples ? samples.normals : vertex_normals;
  const RowMatrixX3d& offsets = at_samples ? samples.offsets : vertex_offsets;
  // The stage as the bake runs it: at the samples, each face's transfer is reduced to the
  // fit's moments as it is traced.
  auto transfer = [&](TransferStats& stats) {
    if (at_samples) trace_face_moments(mesh, scene, samples, c.transfer, &stats);
    else shadowed_transfer(scene, points, normals, c.transfer, &stats, {}, &offsets);
  };

  double best_transfer = INFINITY, best_bare = INFINITY;
  uint64_t rays = 0, occluded = 0;
  std::printf("prtsub bench: %s, %lld %s, order %d, %d rays each\n", c.input.c_str(), static_cast<long long>(points.rows()),
              at == "samples" ? "surface samples" : "vertices", c.transfer.order, c.transfer.rays);
  for (int i = 0; i < repeat; ++i) {
    TransferStats bare, full;
    occluded = bare_occlusion_loop(scene, points, normals, c.transfer, &bare, &offsets);
    transfer(full);
    rays = full.rays;
    best_bare = std::min(best_bare, bare.seconds);
    best_transfer = std::min(best_transfer, full.seconds);
    std::printf("  run %d: bare %.3f s, transfer %.3f s\n", i + 1, bare.seconds, full.seconds);
  }
  const double bare_rps = static_cast<double>(rays) / best_bare, transfer_rps = static_cast<double>(rays) / best_transfer;
  std::printf("  bare loop:  %.2f Mrays/s\n  transfer:   %.2f Mrays/s (%.1f%% of bare)\n", bare_rps / 1e6, transfer_rps / 1e6,
              100 * transfer_rps / bare_rps);
  std::printf("  occluded:   %.1f%% of rays; scene build %.3f s; peak memory %.0f MiB\n",
              100.0 * static_cast<double>(occluded) / static_cast<double>(rays), t_scene, peak_memory_mib());
  if (!c.report.empty()) {
    Report r;
    r.set("command", "bench");
    r.set("input", c.input);
    r.set("order", c.transfer.order);
    r.set("rays_per_vertex", c.transfer.rays);
    r.set("threads", c.transfer.threads);
    r.set("vertices", static_cast<uint64_t>(mesh.num_vertices()));
    r.set("triangles", static_cast<uint64_t>(mesh.num_faces()));
    r.set("at", at);
    r.set("points", static_cast<uint64_t>(points.rows()));
    r.set("rays", rays);
    r.set("repeat", repeat);
    r.set("occluded_fraction", static_cast<double>(occluded) / static_cast<double>(rays));
    r.set("transfer_rays_per_second", transfer_rps);
    r.set("bare_rays_per_second", bare_rps);
    r.set("transfer_over_bare", transfer_rps / bare_rps);
    r.set("seconds_load", t_load);
    r.set("seconds_scene", t_scene);
    r.set("seconds_transfer_best", best_transfer);
    r.set("seconds_bare_best", best_bare);
    r.set("peak_memory_mib", peak_memory_mib());
    r.write(c.report);
  }
  return 0;
}


int cmd_render(int argc, char** argv) {
  std::string input, output, report, size = "800,600", camera_spec = "auto";
  std::vector<std::string> light_specs, rotations;
  double albedo = 0.8, exposure = 1.0;
  bool reference = false, compare_bare = false;
  TransferOptions topt;
  ArgParser args("render",
                 "Renders an asset under SH light: Gouraud-interpolated per-vertex PRT (what a GPU shows), or with\n"
                 "--reference the per-pixel ground truth (transfer computed at every pixel's hit point).");
  args.positional("ASSET", "a .ply asset written by prtsub bake", &input);
  args.option("--light", "SPEC", "env:PATH | sh:c0,c1,... | sun:X,Y,Z[,RADIUS_DEG] | sky[:UPX,UPY,UPZ] | random:SEED | const:R,G,B; lights add up", &light_specs);
  args.option("--light-rotate", "AXIS,DEG", "rotate the light about x, y, z or X,Y,Z", &rotations);
  args.option("--output", "FRAME.png|FRAME.exr", "output frame (required); EXR is linear float RGBA", &output);
  args.alias("-o", "--output");
  args.option("--size", "W,H", "frame size in pixels [default 800,600]", &size);
  args.option("--camera", "auto|eye=X,Y,Z:target=X,Y,Z:up=X,Y,Z:fov=DEG", "camera [default auto]", &camera_spec);
  args.option("--albedo", "A", "diffuse albedo", &albedo, 0.0, 1.0);
  args.option("--exposure", "E", "PNG only: linear radiance is multiplied by E before the sRGB curve", &exposure, 0.0, 1e6);
  args.flag("--reference", "render the per-pixel reference instead of the Gouraud frame", &reference);
  args.option("--rays", "R", "reference: rays per pixel", &topt.rays, 1, 1 << 20);
  args.option("--seed", "S", "reference: random seed", &topt.seed);
  args.option("--threads", "T", "worker threads, 0 for every core", &topt.threads, 0, 1024);
  args.flag("--compare-bare", "reference: also time a bare Embree loop over the same rays (report: bare_rays_per_second)", &compare_bare);
  args.option("--report", "R.json", "also write a flat JSON report", &report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (output.empty()) throw UsageError("render: missing -o FRAME.png|FRAME.exr");
  if (light_specs.empty()) throw UsageError("render: missing --light SPEC");
  int width = 0, height = 0;
  parse_size(size, "--size", width, height);
  check_writable(output);
  if (!report.empty()) check_writable(report);

  Stopwatch clock;
  Asset asset = read_asset(input);
  const double t_load = clock.lap();
  ShLight light = parse_light(light_specs[0], asset.order);
  for (size_t i = 1; i < light_specs.size(); ++i) light += parse_light(light_specs[i], asset.order);
  for (const std::string& r : rotations) light = rotate_light(light, parse_rotation(r));
  Camera camera = camera_spec == "auto" ? auto_camera(bounds(asset.positions), width, height) : parse_camera(camera_spec);
  const double t_light = clock.lap();
  RayScene scene(asset.positions, asset.triangles);
  const double t_scene = clock.lap();
  SurfaceHits hits = trace_primary(scene, camera, width, height, topt.threads);
  const double t_primary = clock.lap();

  Image frame;
  TransferStats stats;
  double bare_rps = 0;
  if (reference) {
    topt.order = asset.order;
    Progress progress("reference", hits.covered(), stderr_is_terminal());
    frame = render_reference(scene, hits, asset.positions, asset.normals, asset.triangles, light, albedo, topt, &stats,
                             [&](size_t n) { progress.add(n); });
    progress.finish();
    if (compare_bare) {
      RowMatrixX3d points, point_normals;
      hit_points(hits, asset.positions, asset.normals, asset.triangles, points, point_normals);
      TransferStats bare;
      bare_occlusion_loop(scene, points, point_normals, topt, &bare);
      bare_rps = static_cast<double>(bare.rays) / std::max(bare.seconds, 1e-9);
    }
  } else {
    frame = shade_gouraud(hits, asset.triangles, vertex_radiance(asset.transfer, light, albedo));
  }
  const double t_shade = clock.lap();
  write_image(output, frame, ImageWriteOptions{exposure});
  const double t_write = clock.lap();
  const double total = clock.total();

  double sum = 0;
  const size_t covered = hits.covered();
  for (size_t i = 0; i < hits.face.size(); ++i)
    if (hits.face[i] >= 0) sum += (frame.pixels[4 * i] + frame.pixels[4 * i + 1] + frame.pixels[4 * i + 2]) / 3.0;
  const double mean = covered ? sum / static_cast<double>(covered) : 0.0;
  std::printf("prtsub render: %s -> %s (%s)\n", input.c_str(), output.c_str(), reference ? "per-pixel reference" : "Gouraud");
  std::printf("  frame:      %dx%d, %zu pixels covered (%.1f%%), mean radiance %.4g\n", width, height, covered,
              100.0 * static_cast<double>(covered) / (static_cast<double>(width) * height), mean);
  std::printf("  camera:     eye %g,%g,%g target %g,%g,%g up %g,%g,%g fov %g\n", camera.eye.x(), camera.eye.y(), camera.eye.z(),
              camera.target.x(), camera.target.y(), camera.target.z(), camera.up.x(), camera.up.y(), camera.up.z(), camera.fov_deg);
  if (reference)
    std::printf("  reference:  %llu rays, %.2f Mrays/s%s\n", static_cast<unsigned long long>(stats.rays),
                static_cast<double>(stats.rays) / std::max(stats.seconds, 1e-9) / 1e6,
                compare_bare ? (" (bare loop " + std::to_string(bare_rps / 1e6).substr(0, 5) + " Mrays/s)").c_str() : "");
  std::printf("  time:       %.3f s total (load %.3f, light %.3f, scene %.3f, primary %.3f, shade %.3f, write %.3f)\n", total,
              t_load, t_light, t_scene, t_primary, t_shade, t_write);
  if (!report.empty()) {
    Report r;
    r.set("command", "render");
    r.set("input", input);
    r.set("output", output);
    r.set("mode", reference ? "reference" : "gouraud");
    r.set("width", width);
    r.set("height", height);
    r.set("triangles", static_cast<uint64_t>(asset.triangles.size()));
    r.set("pixels_covered", static_cast<uint64_t>(covered));
    r.set("mean_radiance", mean);
    r.set("seconds_total", total);
    r.set("seconds_load", t_load);
    r.set("seconds_light", t_light);
    r.set("seconds_scene", t_scene);
    r.set("seconds_primary", t_primary);
    r.set("seconds_shade", t_shade);
    r.set("seconds_write", t_write);
    r.set("seconds_frame", t_primary + t_shade);
    if (reference) {
      r.set("rays", stats.rays);
      r.set("rays_per_pixel", topt.rays);
      r.set("reference_rays_per_second", static_cast<double>(stats.rays) / std::max(stats.seconds, 1e-9));
      if (compare_bare) r.set("bare_rays_per_second", bare_rps);
    }
    r.set("peak_memory_mib", peak_memory_mib());
    r.write(report);
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
  args.option("--report", "R.json", "also write a flat JSON report", &report);
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
  args.option("--report", "R.json", "also write a flat JSON report", &report);
  if (!args.parse(argc, argv, 2)) return 0;
  if (source.empty()) throw UsageError("eval: missing --source INPUT");
  if (!report.empty()) check_writable(report);
  Stopwatch clock;
  Asset asset = read_asset(input);
  std::map<std::string, std::string> meta(asset.metadata.begin(), asset.metadata.end());
  const int asset_rays = meta.count("rays") ? std::atoi(meta["rays"].c_str()) : 256;
  const double crease = meta.count("crease_angle") ? std::atof(meta["crease_angle"].c_str()) : 60.0;
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
      std::printf("prtsub %s\n", kPrtsubVersion);
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
