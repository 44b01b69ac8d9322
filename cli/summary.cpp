#include "cli/summary.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "prtsub/prt/sg_basis.h"
#include "prtsub/prt/sh.h"

namespace prtsub {

void record(Report& r, const MeshDefects& d) {
  r.set("defects_degenerate_faces", d.degenerate_faces);
  r.set("defects_zero_area_faces", d.zero_area_faces);
  r.set("defects_duplicate_faces", d.duplicate_faces);
  r.set("defects_unreferenced_vertices", d.unreferenced_vertices);
  r.set("defects_winding_conflicts", d.winding_conflicts);
  r.set("defects_non_manifold_edges", d.non_manifold_edges);
  r.set("defects_invalid_file_normals", d.invalid_file_normals);
  r.set("defects_corners_without_uv", d.corners_without_uv);
  r.set("welded_vertices", d.welded_vertices);
  r.set("boundary_edges", d.boundary_edges);
  r.set("polygons_triangulated", d.polygons_triangulated);
}

void record(Report& r, const RefineStats& st) {
  r.set("splits", st.splits);
  r.set("pre_refinement_splits", st.pre_refinement_splits);
  r.set("boundary_splits", st.boundary_splits);
  r.set("new_vertices", st.new_vertices);
  r.set("batches", st.batches);
  r.set("non_manifold_edges", st.non_manifold_edges);
  r.set("non_manifold_splits", st.non_manifold_splits);
  r.set("non_manifold_edges_kept", st.non_manifold_edges_kept);
  r.set("min_angle_before_deg", st.min_angle_before_deg);
  r.set("min_angle_after_deg", st.min_angle_after_deg);
  r.set("faces_below_1deg_before", st.faces_below_1deg_before);
  r.set("faces_below_1deg_after", st.faces_below_1deg_after);
  r.set("seconds_refine_rays", st.seconds_signal);
  r.set("seconds_refine_total", st.seconds_total);
  r.set("refine_overhead_fraction", st.seconds_total > 0 ? (st.seconds_total - st.seconds_signal) / st.seconds_total : 0.0);
}

// How the samples were spread: faces by their sample count, in powers of two.
// Vertices by their rays relative to the first round: 1×, 2×, 4×, 8×, 16× and more (the second
// round and --error double a vertex's rays).
void record_ray_spread(Report& r, const std::vector<double>& rays, int first_round) {
  std::vector<size_t> bins(5, 0);
  for (double n : rays) {
    const double ratio = first_round > 0 ? n / first_round : 1.0;
    const long b = ratio > 1 ? std::lround(std::log2(ratio)) : 0;
    ++bins[static_cast<size_t>(std::clamp<long>(b, 0, 4))];
  }
  const char* names[5] = {"1x", "2x", "4x", "8x", "16x_up"};
  for (size_t b = 0; b < 5; ++b) r.set(std::string("vertices_with_rays_") + names[b], bins[b]);
  // The whole distribution: each count that occurs, and its vertices.
  std::map<double, size_t> counts;
  double sum = 0;
  for (double n : rays) ++counts[n], sum += n;
  std::string table;
  for (const auto& [n, k] : counts) table += (table.empty() ? "" : ", ") + std::to_string(static_cast<uint64_t>(n)) + ": " + std::to_string(k);
  r.set("vertex_rays_distribution", table);
  r.set("vertex_rays_mean", rays.empty() ? 0.0 : sum / double(rays.size()));
}

void record_sample_spread(Report& r, const FitData& data) {
  const SurfaceSamples& s = data.samples;
  const size_t F = s.begin.empty() ? 0 : s.begin.size() - 1;
  std::vector<size_t> bins(8, 0);  // 0, 1, 2-3, 4-7, ..., 64+
  for (size_t f = 0; f < F; ++f) {
    size_t n = s.begin[f + 1] - s.begin[f], b = 0;
    while (n > 0 && b < 7) n >>= 1, ++b;
    ++bins[b];
  }
  const char* names[8] = {"0", "1", "2_3", "4_7", "8_15", "16_31", "32_63", "64_up"};
  for (size_t b = 0; b < 8; ++b) r.set(std::string("faces_with_samples_") + names[b], bins[b]);
  r.set("sample_allocation", sample_allocation_name(data.allocation));
  if (data.allocation != SampleAllocation::Pilot) return;
  r.set("pilot_samples", data.plan.pilot_samples);
  r.set("pilot_samples_drawn", data.plan.pilot_drawn);
  r.set("pilot_rays", data.plan.rays);
  r.set("seconds_pilot", data.plan.seconds);
  if (data.plan.screen_samples > 0) {
    r.set("pilot_screen_samples", data.plan.screen_samples);
    r.set("pilot_screen_ratio", data.plan.screen_ratio);
    r.set("pilot_screen_standard_error", data.plan.screen_standard_error);
    r.set("pilot_screened_out", data.plan.screened_out);
  }
  r.set("sampled_faces", data.plan.sampled_faces);
  r.set("interpolated_faces", F - data.plan.sampled_faces);
}

void record(Report& r, const ErrorEstimate& e) {
  r.set("predicted_error_percent", e.percent);
  r.set("predicted_error_standard_error", e.standard_error);
  r.set("predicted_error_samples", e.samples);
}

void record(Report& r, const TopUpStats& t) {
  r.set("top_up_vertices", t.vertices);
  r.set("top_up_rays", t.rays);
  r.set("seconds_top_up", t.seconds);
  r.set("top_up_variance_before", t.variance_before);
  r.set("top_up_variance_after", t.variance_after);
  r.set("top_up_variance_ratio", t.variance_before > 0 ? t.variance_after / t.variance_before : 1.0);
}

void record(Report& r, const FitStats& f, const FitOptions& o, const FitData& data, int sample_rays) {
  r.set("fit", fit_method_name(o.method));
  if (o.method == FitMethod::Point) return;
  r.set("samples", data.samples.size());
  r.set("sample_rays", data.sample_rays > 0 ? data.sample_rays : sample_rays);
  const SampleRaysChoice& c = data.plan.sample_rays;
  r.set("sample_rays_auto", c.rays > 0);
  if (c.rays > 0) {
    // Each candidate's cost relative to the chosen one's, and its measured noise.
    const size_t chosen = size_t(std::find(c.choices.begin(), c.choices.end(), c.rays) - c.choices.begin());
    std::string trials;
    char buf[96];
    for (size_t k = 0; k < c.choices.size() && k < c.cost.size(); ++k) {
      std::snprintf(buf, sizeof buf, "%s%d: %.2f (noise %.3g)", trials.empty() ? "" : ", ", c.choices[k],
                    c.cost[chosen] > 0 ? c.cost[k] / c.cost[chosen] : 1.0, c.noise[k]);
      trials += buf;
    }
    r.set("sample_rays_trials", trials);
    r.set("sample_rays_variation", c.variation);
    r.set("sample_rays_noise_points", static_cast<uint64_t>(c.points));
    r.set("sample_rays_noise_rays", c.rays_traced);
  }
  record_sample_spread(r, data);
  if (o.method != FitMethod::LeastSquares) return;
  r.set("alpha", o.alpha);
  r.set("regularizer", regularizer_name(o.regularizer));
  r.set("mass", mass_matrix_name(o.mass));
  r.set("fit_solver", f.solver);
  r.set("fit_cg_iterations", f.cg_iterations);
  r.set("fit_multigrid_levels", f.multigrid_levels);
  r.set("fit_multigrid_operator_complexity", f.multigrid_operator_complexity);
  // What CG's iterations were: the solution, or the attempt before CHOLMOD took over.
  if (f.cg_iterations > 0)
    r.set("fit_cg_note", f.solver != "cg"    ? "CG iterations first"
                         : f.stiff_rows > 0 ? "CG iterations, " + std::to_string(f.stiff_rows) + " stiff rows solved directly in each"
                                            : std::string("CG iterations"));
  r.set("fit_unsupported_vertices", f.unsupported);
  r.set("fit_stabilizer", f.stabilizer);
  r.set("fit_system_nonzeros", f.system_nonzeros);
  r.set("fit_factor_nonzeros", f.factor_nonzeros);
  r.set("fit_stiff_share", f.stiff_share);
  r.set("fit_stiff_rows", f.stiff_rows);
  r.set("fit_stiff_factor_nonzeros", f.stiff_factor_entries);
  r.set("fit_predicted_factor_nonzeros", f.predicted_factor_entries);
  r.set("solve_memory_mib", f.solve_memory_mib);
  r.set("seconds_fit_assemble", f.seconds_assemble);
  r.set("seconds_fit_assemble_sums", f.seconds_assemble_sums);
  r.set("seconds_fit_assemble_edges", f.seconds_assemble_edges);
  r.set("seconds_fit_assemble_rows", f.seconds_assemble_rows);
  r.set("seconds_fit_factor", f.seconds_factor);
  r.set("seconds_fit_solve", f.seconds_solve);
  r.set("noise_weighting", o.weigh_by_noise);
  r.set("kept_correction", f.kept_correction);
  r.set("fit_unshadowed_iterations", f.unshadowed_iterations);
  r.set("seconds_fit_unshadowed", f.seconds_unshadowed);
  r.set("non_negative", non_negative_name(o.non_negative));
  r.set("non_negative_limited_vertices", f.limited_vertices);
}

void record(Report& r, const BakeResult& res, const BakeOptions& o) {
  const Mesh& mesh = res.mesh;
  const int order = o.signal == AssetSignal::Ao ? 1
                    : o.sg_lobes > 0        ? sg_shading_order(sg_basis(o.sg_lobes))
                    : res.order.order > 0   ? res.order.order
                                            : o.transfer.order;
  r.set("order", order);
  r.set("coefficients", o.sg_lobes > 0 ? o.sg_lobes : sh_count(order));
  r.set("basis", o.sg_lobes > 0 ? "sg:" + std::to_string(o.sg_lobes) : std::string("sh"));
  if (o.sg_lobes > 0) r.set("sg_encoding", o.sg_signed ? "signed" : "non-negative");
  r.set("order_auto", res.order.order > 0);
  if (res.order.order > 0) {
    const OrderChoice& c = res.order;
    r.set("order_truncation_percent", c.truncation_percent[static_cast<size_t>(c.order - 1)]);
    r.set("order_tolerance_percent", c.tolerance_percent);
    r.set("order_reached", c.reached);
    r.set("order_pilot_points", c.points);
    r.set("order_pilot_rays", c.rays);
    r.set("order_max", static_cast<int>(c.truncation_percent.size()));
    r.set("seconds_order", c.seconds);
    for (size_t n = 0; n < c.truncation_percent.size(); ++n) {
      r.set("order_truncation_percent_" + std::to_string(n + 1), c.truncation_percent[n]);
      r.set("order_noise_percent_" + std::to_string(n + 1), c.noise_percent[n]);
    }
    std::string table;
    for (size_t n = 0; n < c.truncation_percent.size(); ++n) {
      char cell[64];
      std::snprintf(cell, sizeof cell, "%s%zu: %.2f/%.2f", n ? ", " : "", n + 1, c.truncation_percent[n], c.noise_percent[n]);
      table += cell;
    }
    r.set("order_table", table);
    r.set("order_why", c.reached ? (o.order_choice.tolerance_percent > 0 ? "within --order-tolerance" : "below the bake's own noise at that order")
                                 : "not known at --max-order, and no lower order got below its tolerance");
  }
  // --error without --rays: the first round's count it chose (o.transfer.rays is the flag's default)
  r.set("rays_per_vertex", res.first_round.rays > 0 ? res.first_round.rays : o.transfer.rays);
  r.set("seed", o.transfer.seed);
  r.set("estimator", estimator_name(o.transfer.estimator));
  r.set("crease_angle", mesh.crease_angle_deg);
  r.set("refine", refinement_name(o.refine));
  r.set("triangles_in", mesh.input_triangles);
  r.set("vertices_in", mesh.input_vertices);
  r.set("triangles_out", mesh.num_faces());
  r.set("vertices_out", mesh.num_vertices());
  r.set("positions_out", static_cast<uint64_t>(mesh.positions.rows()));
  r.set("normals_from_file", mesh.normals_from_file);
  r.set("normals", mesh.normals_from_file ? "from file" : "computed");
  r.set("uvs", mesh.has_uv() ? "; UVs from file" : "");
  if (o.refine == Refinement::Adaptive || o.refine == Refinement::Auto) {
    r.set("budget", o.adaptive.budget);
    r.set("estimate", estimate_name(o.estimate));
    r.set("batch", o.adaptive.batch);
    r.set("max_edge", o.adaptive.max_edge);
    r.set("simplified", res.simplified);
    if (res.simplified) {
      const SimplifyStats& st = res.simplify;
      r.set("simplify_metric", simplify_metric_name(o.simplify.metric));
      r.set("simplify_min_angle_deg", o.simplify.min_angle_deg);
      r.set("collapses", st.collapses);
      r.set("locked_vertices", st.locked_vertices);
      r.set("corner_collapses", st.corner_collapses);
      r.set("moved_vertices", st.moved.size());
      r.set("kept_faces", st.kept_faces);
      r.set("min_angle_after_deg", st.min_angle_after_deg);
      r.set("faces_below_min_angle", st.faces_below_min_angle);
      r.set("seconds_simplify", st.seconds);
      r.set("refused_flip", st.refused_flip);
      r.set("refused_angle", st.refused_angle);
      r.set("refused_line", st.refused_line);
      r.set("refused_crease_side", st.refused_crease_side);
      r.set("refused_surface", st.refused_surface);
      r.set("surface_tolerance_percent", 100 * st.surface_tolerance);
    }
    if (!res.simplified || o.refine == Refinement::Auto) record(r, res.refine);
    if (o.refine == Refinement::Auto) {
      r.set("auto_share", o.auto_share), r.set("simplified_to", res.simplify.faces_after);
      r.set("auto_cycles", res.auto_cycles), r.set("auto_cycle_collapses", res.auto_cycle_collapses);
      r.set("auto_cycle_share", o.auto_cycle_share);
    }
  }
  if (o.refine == Refinement::Uniform) r.set("levels", o.uniform.levels), r.set("scheme", uniform_scheme_name(o.uniform.scheme));
  r.set("signal", asset_signal_name(o.signal));
  r.set("bounces", res.bounce.passes);
  r.set("channels", o.signal == AssetSignal::Ao || o.sg_lobes > 0 ? 1 : std::max(transfer_channels(res.transfer.cols()), 1));
  if (o.albedo_colour.coloured()) r.set("albedo_source", albedo_description(o.albedo_colour));
  r.set("bounce_rekeyed_at", res.rekeyed_at);
  if (res.bounce.passes > 0) {
    if (o.albedo_colour.coloured()) r.set("albedo", albedo_description(o.albedo_colour) + ", RGB transfer");
    else r.set("albedo", o.bounce.albedo);
    r.set("bounces_auto", o.bounce.until_converged);
    r.set("bounce_change_percent", res.bounce.change_percent.back());
    for (size_t k = 0; k < res.bounce.change_percent.size(); ++k)
      r.set("bounce_change_percent_" + std::to_string(k + 1), res.bounce.change_percent[k]);
    r.set("bounce_rays", res.bounce.rays);
    r.set("bounce_rays_per_vertex", res.bounce_rays);
    r.set("bounce_rays_chosen", res.bounce_rays_chosen);
    r.set("bounce_cached", res.bounce.cached);
    r.set("bounce_cache_mib", res.bounce.cache_mib);
    r.set("seconds_bounce", res.seconds_bounce);
  }
  record(r, res.fit, o.fit, res.fit_data, o.sample_rays);
  if (o.fit.method == FitMethod::LeastSquares) {
    r.set("alpha", res.alpha);
    r.set("alpha_auto", !res.alpha_trials.empty());
    std::string trials;
    char buf[64];
    for (const auto& [a, e] : res.alpha_trials) std::snprintf(buf, sizeof buf, "%s%g: %.3f%%", trials.empty() ? "" : ", ", a, e), trials += buf;
    if (!trials.empty()) r.set("alpha_trials", trials);
    r.set("fit_unshadowed_projection", resolve_bake_options(o).fit.unshadowed_order > 0 && !(res.simplified && res.simplify.collapses > 0));
  }
  if (res.simplified && res.simplify.collapses > 0 && (o.refine != Refinement::Auto || res.refine.splits == 0)) r.set("alpha", o.simplified_alpha);
  if (res.fit_data.allocation == SampleAllocation::Pilot) record(r, res.top_up), record(r, res.predicted);
  else {  // both ways: a second round and a hold-out without a pilot
    if (res.top_up.rays > 0) record(r, res.top_up);
    if (res.fit_data.plan.holdout.size() > 0) {
      record(r, res.predicted);
      r.set("predicted_error_rays", res.fit_data.plan.holdout.rays);  // per sample, after any tracing again
      r.set("holdout_sharpen_rays", res.holdout_sharpen_rays);
    }
  }
  const bool early = early_stop_on(o);
  record_ray_spread(r, res.vertex_rays, early ? o.round_rays : o.transfer.rays);
  r.set("early_stop", early);
  if (early) {
    r.set("early_stop_first_rays", o.round_rays);
    r.set("early_stop_noise_percent", o.stop_noise_percent);
    r.set("early_stop_rounds", res.early_stop.rounds);
    r.set("early_stop_rays", res.early_stop.rays);
    size_t at_first = 0;
    if (!res.early_stop.histogram.empty()) at_first = res.early_stop.histogram[0];
    r.set("early_stop_at_first_round", at_first);
  }
  if (o.target_error > 0) {
    r.set("target_error_percent", o.target_error);
    r.set("target_rays", res.target_rays);
    r.set("target_rounds", res.target_rounds);
    r.set("target_samples", static_cast<uint64_t>(res.target_samples));
    r.set("target_sample_rays", res.target_sample_rays);
    r.set("target_sample_rounds", res.target_sample_rounds);
    r.set("seconds_target", res.seconds_target);
    r.set("target_holdout_rays", res.target_holdout_rays);
    r.set("holdout_rays_per_sample", res.fit_data.plan.holdout.rays);
    if (res.predicted_direct.samples > 0) {
      r.set("predicted_direct_error_percent", res.predicted_direct.percent);
      r.set("target_bounce_rounds", res.target_bounce_rounds);
      r.set("target_direct_rounds", res.target_direct_rounds);
    }
    if (res.first_round.rays > 0) {
      r.set("target_first_round_rays", res.first_round.rays);
      r.set("target_first_round_points", static_cast<uint64_t>(res.first_round.points));
      r.set("target_first_round_pilot_rays", res.first_round.pilot_rays);
      const int counts[] = {32, 64, 128, 256};
      std::string noise;
      char buf[48];
      for (size_t k = 0; k < res.first_round.noise_percent.size() && k < 4; ++k)
        std::snprintf(buf, sizeof buf, "%s%d: %.3f%%", noise.empty() ? "" : ", ", counts[k], res.first_round.noise_percent[k]), noise += buf;
      r.set("target_first_round_noise", noise);
      r.set("target_first_round_decay", res.first_round.decay);
    }
  }
  if (o.signal == AssetSignal::Ao) r.set("clamped_values", res.clamped);
  const double trace_seconds = res.seconds_transfer + res.refine.seconds_signal + res.seconds_samples + res.seconds_top_up;
  r.set("rays", res.rays);
  r.set("seconds_tracing", trace_seconds);
  r.set("rays_per_second", static_cast<double>(res.rays) / std::max(trace_seconds, 1e-9));
  r.set("mrays_per_second", static_cast<double>(res.rays) / std::max(trace_seconds, 1e-9) / 1e6);
  r.set("seconds_bake", res.seconds_total);
  r.set("seconds_scene", res.seconds_scene);
  r.set("seconds_transfer", res.seconds_transfer);
  r.set("seconds_refine", res.seconds_refine);
  r.set("seconds_samples", res.seconds_samples);
  r.set("seconds_top_up", res.seconds_top_up);
  r.set("seconds_fit", res.seconds_fit);
  r.set("warnings", res.warnings.size());
  record(r, mesh.defects);
}

void print_bake_summary(const Report& r) {
  const bool adaptive = r.format("{refine}") == "adaptive" || r.format("{refine}") == "auto", uniform = r.format("{refine}") == "uniform";
  const bool ao = r.format("{signal}") == "ao";
  const std::string fit = r.format("{fit}");
  r.print(stdout,
          {"prtsub bake: {input} -> {output}", "  input:      {triangles_in} triangles, {vertices_in} vertices",
           "  output:     {triangles_out} triangles, {vertices_out} vertices ({positions_out} positions; normals {normals}{uvs})",
           "  tolerated:  {defects_degenerate_faces} degenerate faces dropped, {defects_zero_area_faces} zero-area faces, "
           "{defects_duplicate_faces} duplicate faces,",
           "              {defects_unreferenced_vertices} unreferenced vertices dropped, {defects_winding_conflicts} winding "
           "conflicts, {defects_non_manifold_edges} non-manifold edges,",
           "              {defects_invalid_file_normals} invalid file normals, {defects_corners_without_uv} corners without UVs (0, 0)",
           "  topology:   {boundary_edges} boundary edges, {welded_vertices} vertices welded, {polygons_triangulated} polygons "
           "triangulated"});
  if (adaptive && r.format("{simplified}") == "yes")
    r.print(stdout, {"  simplify:   to the budget, metric {simplify_metric}: {collapses} half-edge collapses (OpenMesh's Decimater), "
                     "{corner_collapses} of crease corners ({moved_vertices} render vertices moved and traced again there),",
                     "              {locked_vertices} vertices locked (ends of creases, creases at a boundary), {kept_faces} faces kept "
                     "as they were",
                     "              min angle {min_angle_after_deg:3}° after ({faces_below_min_angle} faces below "
                     "{simplify_min_angle_deg:1}°, none worse than the faces a collapse replaced); {seconds_simplify:3} s",
                     "              guards refused (per evaluation): {refused_flip} flips, {refused_angle} angles, "
                     "{refused_line} boundary or feature lines, {refused_crease_side} crease sides, {refused_surface} "
                     "surface moves (tolerance reached {surface_tolerance_percent:2}% of the diagonal)"});
  if (r.format("{refine}") == "auto")
    r.print(stdout, {"  both ways:  simplified to {simplified_to} triangles (auto share {auto_share}), then refined to the budget; "
                     "{auto_cycles} further cycle(s) of {auto_cycle_collapses} collapses (share {auto_cycle_share} each) and refining back"});
  if (adaptive && (r.format("{simplified}") != "yes" || r.format("{refine}") == "auto"))
    r.print(stdout, {"  refine:     adaptive, estimate {estimate}, {splits} splits ({boundary_splits} boundary, "
                     "{pre_refinement_splits} pre-refinement) in {batches} batches",
                     "              min angle {min_angle_before_deg:3}° before, {min_angle_after_deg:3}° after; faces "
                     "below 1°: {faces_below_1deg_before} before, {faces_below_1deg_after} after",
                     "              {non_manifold_edges} non-manifold edges, {non_manifold_splits} splits of one (in all "
                     "their faces at once)",
                     "              {seconds_refine_total:3} s, of which {seconds_refine_rays:3} s tracing new vertices "
                     "(overhead {refine_overhead_fraction:%1})"});
  if (uniform) r.print(stdout, {"  refine:     uniform (OpenSubdiv, {scheme}), {levels} levels, {seconds_refine:3} s"});
  if (ao)
    r.print(stdout, {"  signal:     ambient occlusion, {rays_per_vertex} rays per vertex, seed {seed}; {clamped_values} values "
                     "clamped into [0, 1]"});
  else if (r.format("{basis}") != "sh")
    r.print(stdout, {"  transfer:   {coefficients} spherical-Gaussian lobes ({sg_encoding}, relit through order {order}), "
                     "{rays_per_vertex} rays per vertex, seed {seed}"});
  else
    r.print(stdout, {"  transfer:   order {order} ({coefficients} coefficients), {rays_per_vertex} rays per vertex, seed {seed}"});
  if (r.format("{early_stop}") == "yes")
    r.print(stdout, {"  early stop: from {early_stop_first_rays} rays, {early_stop_rounds} doubling rounds to at most {rays_per_vertex} "
                     "(noise {early_stop_noise_percent}%); {early_stop_at_first_round} vertices stopped after the first; mean "
                     "{vertex_rays_mean:1} rays per vertex",
                     "              vertices by rays: {vertex_rays_distribution}"});
  if (r.format("{order_auto}") == "yes")
    r.print(stdout, {"  order auto: {order}: what it leaves out, {order_truncation_percent:3}% of ||t_unshadowed||, is {order_why} "
                     "({order_tolerance_percent:3}%); pilot of {order_pilot_points} vertices, {seconds_order:3} s",
                     "              per order, truncation/noise %: {order_table}"});
  if (r.number("bounces") > 0)
    r.print(stdout, {"  bounces:    {bounces} of interreflection, albedo {albedo}; the last added {bounce_change_percent:3}% of "
                     "||t_unshadowed|| ({bounce_rays} rays, {seconds_bounce:3} s)"});
  if (r.number("bounce_rekeyed_at") > 0)
    r.print(stdout, {"              refinement turned to keys on the bounced light at {bounce_rekeyed_at} triangles (--bounce-rekey)"});
  if (fit == "average")
    r.print(stdout, {"  fit:        average of {samples} surface samples ({sample_rays} rays each, {seconds_samples:3} s), averaged in "
                     "{seconds_fit:3} s"});
  if (fit == "lsq") {
    r.print(stdout, {"  fit:        least squares, {regularizer} regulariser, alpha {alpha}, {mass} mass; {samples} surface "
                     "samples ({sample_rays} rays each, {seconds_samples:3} s)"});
    r.print(stdout, {"              alpha auto: the lowest held-out error of {alpha_trials}"});
    if (r.format("{sample_rays_auto}") == "yes")
      r.print(stdout, {"              rays per sample: {sample_rays} for the same sample rays; each choice's modelled error against "
                       "it and a sample's noise: {sample_rays_trials} (16 is left only below 0.8 of its error); variation "
                       "{sample_rays_variation}, noise measured on {sample_rays_noise_points} samples ({sample_rays_noise_rays} rays)"});
    if (r.has("pilot_samples"))
      r.print(stdout, {"              pilot: {pilot_samples} of {pilot_samples_drawn} samples traced ({pilot_rays} rays, {seconds_pilot:3} s) found {sampled_faces} "
                       "faces where interpolation fails; {interpolated_faces} left to it"});
    if (r.has("pilot_screen_samples"))
      r.print(stdout, {r.format("{pilot_screened_out}") == "yes"
                           ? "              screen: on {pilot_screen_samples} samples the variation inside the faces is {pilot_screen_ratio:3} "
                             "(+- {pilot_screen_standard_error:3}) of the vertices' noise: the pilot stopped there, every face left to interpolation"
                           : "              screen: on {pilot_screen_samples} samples the variation inside the faces is {pilot_screen_ratio:3} "
                             "(+- {pilot_screen_standard_error:3}) of the vertices' noise: the pilot goes on"});
    if (r.has("pilot_samples"))
      r.print(stdout, {
                       "              faces by samples: 0: {faces_with_samples_0}, 1: {faces_with_samples_1}, 2-3: "
                       "{faces_with_samples_2_3}, 4-7: {faces_with_samples_4_7}, 8-15: {faces_with_samples_8_15}, 16-31: "
                       "{faces_with_samples_16_31}, 32-63: {faces_with_samples_32_63}, 64+: {faces_with_samples_64_up}",
                       "              vertex rays: {top_up_rays} more at the {top_up_vertices} noisiest vertices ({seconds_top_up:3} s); "
                       "their summed variance x{top_up_variance_ratio:3}",
                       "              vertices by rays: 1x: {vertices_with_rays_1x}, 2x: {vertices_with_rays_2x}, 4x: "
                       "{vertices_with_rays_4x}, 8x: {vertices_with_rays_8x}, 16x+: {vertices_with_rays_16x_up}"});
    else if (r.has("top_up_rays"))
      r.print(stdout, {"              vertex rays: {top_up_rays} more at the {top_up_vertices} noisiest of the input's vertices "
                       "({seconds_top_up:3} s); their summed variance x{top_up_variance_ratio:3}"});
    const std::string cg = r.has("fit_cg_note") ? r.format(", {fit_cg_iterations} {fit_cg_note}") : "";
    std::printf("%s\n", r.format("              solve {seconds_fit:3} s (assemble {seconds_fit_assemble:3}, factor "
                                 "{seconds_fit_factor:3}, solve {seconds_fit_solve:3}; {fit_solver}" + cg +
                                 "), {solve_memory_mib:1} MiB; {fit_unsupported_vertices} vertices kept at their point values")
                            .c_str());
    r.print(stdout, {"              weighed by noise: {kept_correction:%1} of the fit's correction kept on average; non-negative "
                     "({non_negative}): {non_negative_limited_vertices} vertices limited"});
    if (r.number("fit_unshadowed_iterations") > 0)
      r.print(stdout, {"              unshadowed curvature projected exactly onto the mesh ({fit_unshadowed_iterations} CG passes, "
                       "{seconds_fit_unshadowed:3} s, no rays)"});
  }
  if (r.has("predicted_error_percent"))
    std::printf("%s\n", r.format("  error:      {predicted_error_percent:3}% (± {predicted_error_standard_error:3}%) of ||t_unshadowed||, "
                                 "measured on {predicted_error_samples} " +
                                 std::string(r.has("pilot_samples") ? "held-out pilot samples"
                                                                    : "samples held out of the input's surface ({predicted_error_rays} rays each)") +
                                 ": what prtsub eval should find")
                            .c_str());
  if (r.has("target_error_percent"))
    r.print(stdout, {"              target {target_error_percent}%: first round {target_first_round_rays} rays per vertex (a pilot of "
                     "{target_first_round_points} vertices predicts noise R^-{target_first_round_decay:2}, at 32-256: {target_first_round_noise})",
                     "              target {target_error_percent}%: {target_rays} more vertex rays in {target_rounds} rounds, "
                     "{target_samples} more samples in {target_sample_rounds}, the hold-out at {holdout_rays_per_sample} rays per sample "
                     "({target_holdout_rays} rays; {seconds_target:3} s)"});
  if (r.has("predicted_direct_error_percent"))
    r.print(stdout, {"              with bounces: the direct light's error {predicted_direct_error_percent:3}%; the bounced error above is "
                     "measured against paths traced from the held-out samples ({target_holdout_rays} rays with the passes' noise); bounce "
                     "passes first at {bounce_rays_chosen} rays per vertex, at {bounce_rays_per_vertex} after {target_bounce_rounds} rounds of more bounce rays and "
                     "{target_direct_rounds} of more direct rays"});
  if (r.has("merged_parts"))
    r.print(stdout, {"  rays:       {rays}, traced by {merged_shards} shards in {merged_phases} phases ({merged_parts}) and replayed here"});
  else
    r.print(stdout, {"  rays:       {rays} in {seconds_tracing:3} s ({mrays_per_second:2} Mrays/s)"});
  r.print(stdout, {"  time:       {seconds_total:3} s total (load {seconds_load:3}, scene {seconds_scene:3}, transfer "
                   "{seconds_transfer:3}, refine {seconds_refine:3}, samples {seconds_samples:3}, vertex rays {seconds_top_up:3}, fit {seconds_fit:3}, write "
                   "{seconds_write:3});",
                   "              peak memory {peak_memory_mib:0} MiB"});
}

}  // namespace prtsub
