// The comparison behind every claim about refinement. All runs bake the same input with the
// same order, rays and seed, and are judged by one reference (the same seeded points, 8x the
// rays), so their errors differ only by where their vertices are. Uniform levels run at their
// own triangle counts; adaptive runs at exactly those counts and at the requested budgets.
// The page is self-contained: inline SVG plots and PNG frames as data URIs.
#include "cli/commands.h"
#include "cli/images.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "cli/args.h"
#include "cli/escape.h"
#include "cli/options.h"
#include "cli/specs.h"
#include "cli/report.h"
#include "cli/pareto.h"
#include "cli/plot.h"
#include "cli/viewer_page.h"
#include "prtsub/prt/base64.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/lights.h"
#include "prtsub/prt/render.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

struct Row {
  std::string method, estimate, fit = "point";
  size_t triangles = 0, vertices = 0;
  double rms = 0, p95 = 0, seconds = 0;
};

std::vector<size_t> parse_budgets(const std::string& s) {
  std::vector<size_t> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    long long v = std::strtoll(item.c_str(), &end, 10);
    if (item.empty() || end != item.c_str() + item.size() || v <= 0) throw UsageError("--budgets: expected positive integers separated by commas, got '" + s + "'");
    out.push_back(static_cast<size_t>(v));
  }
  if (out.empty()) throw UsageError("--budgets: at least one budget");
  return out;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}


std::string fmt(double v, int digits = 4) { return format_number(v, digits); }

struct CompareCli {
  BakeCli bake;
  std::string out_dir, budgets = "", estimates = "relative,shadow,curvature,length,probe,root", frame_size = "480,360";
  std::vector<std::string> lights;
  int max_levels = 4, eval_points = 20000, frame_rays = 256;
  bool pareto = false, simplify = false;
  std::string grid_rays = "64,256,1024", grid_samples = "0,4,16,64", grid_sample_rays = "4,16,64", targets;

  void add(ArgParser& args) {
    bake.add_common(args);
    args.option("--budgets", "T1,T2,...", "adaptive triangle budgets (required unless --pareto)", &budgets);
    args.option("--output", "DIR", "output directory (required; created)", &out_dir);
    args.alias("-o", "--output");
    args.option("--estimates", "LIST", "adaptive estimates to run [default relative,shadow,curvature,length,probe,root]", &estimates);
    args.option("--max-levels", "K", "uniform levels to try, up to the largest budget", &max_levels, 1, 8);
    add_batch_option(args, bake.bake.adaptive);
    args.option("--eval-points", "N", "reference points", &eval_points, 100, 10000000);
    args.option("--light", "SPEC", "light of the frames [default sky and sun:1,3,2]", &lights);
    args.option("--frame-size", "W,H", "frame size [default 480,360]", &frame_size);
    args.option("--frame-rays", "R", "rays per pixel of the reference frame", &frame_rays, 1, 1 << 20);
    args.flag("--simplify", "also simplify to 50%, 25% and 10% of the input's triangles, ranked by the transfer and by the "
              "geometry alone (rows 'simplify transfer' and 'simplify geometry', judged by closest point), and both ways (rows 'auto')", &simplify);
    args.flag("--pareto", "also bake the input unrefined under a grid of fixed settings, the default and --error targets: "
              "error against bake seconds (DIR/pareto.csv, pareto.json)", &pareto);
    args.option("--grid-rays", "R1,R2,...", "pareto: rays per vertex [default 64,256,1024]", &grid_rays);
    args.option("--grid-samples", "S1,S2,...", "pareto: surface samples per triangle, 0 for point sampling [default 0,4,16,64]", &grid_samples);
    args.option("--grid-sample-rays", "Q1,Q2,...", "pareto: rays per surface sample [default 4,16,64]", &grid_sample_rays);
    args.option("--targets", "E1,E2,...", "pareto: --error targets in percent [default 0.9, 0.8 and 0.7 of the default's predicted error]",
                &targets);
    bake.add_fit(args);
  }

  ParetoSpec pareto_spec() const {
    ParetoSpec p;
    p.vertex_rays.clear(), p.samples.clear(), p.sample_rays.clear();
    for (double v : parse_numbers(grid_rays, "--grid-rays", 1, 1 << 20)) p.vertex_rays.push_back(static_cast<int>(v));
    p.samples = parse_numbers(grid_samples, "--grid-samples", 0, 1e6);
    for (double v : parse_numbers(grid_sample_rays, "--grid-sample-rays", 2, 1 << 20)) p.sample_rays.push_back(static_cast<int>(v));
    if (!targets.empty()) p.targets = parse_numbers(targets, "--targets", 1e-6, 1e6);
    return p;
  }

 private:
  static std::vector<double> parse_numbers(const std::string& s, const char* option, double lo, double hi) {
    std::vector<double> out;
    for (const std::string& item : split(s)) {
      char* end = nullptr;
      const double v = std::strtod(item.c_str(), &end);
      if (item.empty() || end != item.c_str() + item.size() || !(v >= lo && v <= hi))
        throw UsageError(std::string(option) + ": expected numbers in [" + fmt(lo) + ", " + fmt(hi) + "] separated by commas, got '" + s + "'");
      out.push_back(v);
    }
    if (out.empty()) throw UsageError(std::string(option) + ": at least one value");
    return out;
  }
};

// The plan: the unrefined input, uniform levels up to the largest budget, adaptive at every
// uniform count and every budget, under every estimate. Returns the runs and the triangle
// count the frames are shown at (uniform level 3, or the first budget).
std::vector<BakeOptions> plan_runs(const BakeOptions& base, size_t source_faces, const std::vector<size_t>& budgets,
                                   const std::vector<EdgeEstimate>& estimates, int max_levels, bool simplify, size_t& frame_count) {
  const size_t largest = budgets.empty() ? 0 : *std::max_element(budgets.begin(), budgets.end());
  std::vector<BakeOptions> plan{base};
  std::vector<size_t> counts = budgets;
  frame_count = 0;
  for (int k = 1; k <= max_levels; ++k) {
    const size_t count = source_faces << (2 * k);
    if (count > largest * 5 / 4) break;
    BakeOptions u = base;
    u.refine = Refinement::Uniform, u.uniform.levels = k;
    plan.push_back(u);
    counts.push_back(count);
    if (k == std::min(3, max_levels)) frame_count = count;
  }
  if (frame_count == 0) frame_count = budgets.empty() ? source_faces : budgets.front();
  std::sort(counts.begin(), counts.end());
  counts.erase(std::unique(counts.begin(), counts.end()), counts.end());
  for (size_t count : counts)
    for (EdgeEstimate e : estimates) {
      if (count <= source_faces) continue;
      BakeOptions a = base;
      a.refine = Refinement::Adaptive, a.adaptive.budget = count, a.estimate = e;
      // The fit joins the default estimate's runs; the others compare estimates, point-sampled.
      if (e != BakeOptions{}.estimate) a.fit.method = FitMethod::Point;
      plan.push_back(a);
    }
  if (simplify)
    for (size_t share : {50, 25, 10})
      for (SimplifyMetric m : {SimplifyMetric::Transfer, SimplifyMetric::Geometry}) {
        BakeOptions a = base;
        a.refine = Refinement::Adaptive, a.adaptive.budget = std::max<size_t>(1, source_faces * share / 100), a.simplify.metric = m;
        plan.push_back(a);
        if (m == SimplifyMetric::Transfer) {  // both ways at the same count
          a.refine = Refinement::Auto;
          plan.push_back(a);
        }
      }
  return plan;
}

// A fitted run also carries its point-sampled values: two rows from one bake, the point row
// timed without the samples and the fit.
std::vector<Row> evaluate_run(const BakeOptions& s, const BakeResult& r, const Reference& ref) {
  std::vector<std::pair<std::string, const RowMatrixXd*>> values = {{"point", &r.point}};
  if (s.fit.method != FitMethod::Point) values.push_back({fit_method_name(s.fit.method), &r.transfer});
  std::vector<Row> rows;
  for (const auto& [fit, v] : values) {
    // A simplified mesh's faces do not lie in the source's: its points are located by closest point.
    const EvalResult e = r.simplified ? evaluate_by_closest_point(ref, vertex_positions(r.mesh), r.mesh.triangles, *v, s.transfer.threads)
                                      : evaluate(ref, vertex_positions(r.mesh), r.mesh.triangles, r.mesh.source_face, *v);
    Row row;
    const bool both_ways = s.refine == Refinement::Auto;
    row.method = both_ways ? "auto" : r.simplified ? "simplify" : refinement_name(s.refine);
    row.estimate = both_ways ? estimate_name(s.estimate)
                   : r.simplified ? simplify_metric_name(s.simplify.metric) : s.refine == Refinement::Adaptive ? estimate_name(s.estimate) : "";
    row.fit = fit;
    row.triangles = r.mesh.num_faces();
    row.vertices = r.mesh.num_vertices();
    row.rms = e.rms_percent, row.p95 = e.p95_percent;
    row.seconds = fit == "point" ? r.seconds_total - r.seconds_samples - r.seconds_fit : r.seconds_total;
    rows.push_back(row);
  }
  return rows;
}

void write_tables(const std::string& dir, const std::string& input, const BakeOptions& base, const Reference& ref,
                  const std::vector<Row>& rows) {
  std::ostringstream csv, json;
  csv << "method,estimate,fit,triangles,vertices,rms_percent,p95_percent,seconds\n";
  json << "{\n  \"input\": " << json_quote(input) << ",\n  \"order\": " << base.transfer.order << ",\n  \"rays\": " << base.transfer.rays
       << ",\n  \"reference_points\": " << ref.points.rows() << ",\n  \"reference_rays\": " << ref.rays
       << ",\n  \"noise_floor_percent\": " << fmt(100 * ref.noise_floor, 6) << ",\n  \"runs\": [\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    csv << r.method << "," << r.estimate << "," << r.fit << "," << r.triangles << "," << r.vertices << "," << fmt(r.rms, 6) << ","
        << fmt(r.p95, 6) << "," << fmt(r.seconds, 6) << "\n";
    json << "    {\"method\": \"" << r.method << "\", \"estimate\": \"" << r.estimate << "\", \"fit\": \"" << r.fit
         << "\", \"triangles\": " << r.triangles << ", \"vertices\": " << r.vertices << ", \"rms_percent\": " << fmt(r.rms, 6)
         << ", \"p95_percent\": " << fmt(r.p95, 6) << ", \"seconds\": " << fmt(r.seconds, 6) << "}"
         << (i + 1 < rows.size() ? ",\n" : "\n");
  }
  json << "  ]\n}\n";
  write_file_atomically(dir + "/results.csv", csv.str());
  write_file_atomically(dir + "/results.json", json.str());
}

// Every heat map of the page on one absolute scale: yellow at this fraction of the reference
// frame's mean radiance, so two maps can be compared by eye.
constexpr double kHeatScale = 0.25;

// The heat maps' colour bar, from kHeatStops.
std::string heat_colour_bar() {
  std::ostringstream o;
  o << "<div><svg xmlns='http://www.w3.org/2000/svg' width='480' height='46' font-family='sans-serif' font-size='12'><defs>"
       "<linearGradient id='heat'>";
  for (int k = 0; k < 5; ++k) {
    char colour[8];
    std::snprintf(colour, sizeof colour, "#%02x%02x%02x", int(std::lround(255 * kHeatStops[k][0])), int(std::lround(255 * kHeatStops[k][1])),
                  int(std::lround(255 * kHeatStops[k][2])));
    o << "<stop offset='" << 25 * k << "%' stop-color='" << colour << "'/>";
  }
  o << "</linearGradient></defs><rect x='10' y='4' width='400' height='16' fill='url(#heat)' stroke='#999'/>";
  for (int k = 0; k <= 4; ++k)
    o << "<text x='" << 10 + 100 * k << "' y='36' text-anchor='middle'>" << fmt(100 * kHeatScale * k / 4, 3) << (k == 4 ? "% or more" : "%")
      << "</text>";
  o << "</svg></div>";
  return o.str();
}

// Frames at the frame count, in the page's order: the per-pixel reference, then uniform and
// adaptive, each with point and (if it fitted) fitted values, each frame with its heat map.
struct Frame {
  std::string label, caption, png, heat_png;
};

std::vector<Frame> render_frames(const CompareCli& c, const BakeOptions& base, const Mesh& source, const RayScene& source_scene,
                                 const std::map<std::string, BakeResult>& keep) {
  std::vector<Frame> frames;
  int fw = 0, fh = 0;
  parse_size(c.frame_size, "--frame-size", fw, fh);
  const ShLight light = parse_lights(c.lights, base.transfer.order);
  const Camera cam = auto_camera(bounds(source.positions), fw, fh);
  const SurfaceHits ref_hits = trace_primary(source_scene, cam, fw, fh, base.transfer.threads);
  TransferOptions fo = base.transfer;
  fo.rays = c.frame_rays;
  const Image reference = render_reference(source_scene, ref_hits, vertex_positions(source), source.normals, source.triangles, light, 0.8, fo);
  cli_write_image(c.out_dir + "/frame_reference.png", reference);
  frames.push_back({"per-pixel reference", std::to_string(source.num_faces()) + " source triangles, " + std::to_string(c.frame_rays) +
                    " rays a pixel", read_file_bytes(c.out_dir + "/frame_reference.png"), ""});
  // "uniform" sorts after "adaptive ..."; the page shows uniform first.
  std::vector<const std::pair<const std::string, BakeResult>*> runs;
  for (const auto& run : keep) runs.push_back(&run);
  std::stable_sort(runs.begin(), runs.end(), [](auto* a, auto* b) { return (a->first == "uniform") > (b->first == "uniform"); });
  for (const auto* run : runs) {
    const std::string& name = run->first;
    const BakeResult& r = run->second;
    const RayScene scene(vertex_positions(r.mesh), r.mesh.triangles);
    const SurfaceHits hits = trace_primary(scene, cam, fw, fh, base.transfer.threads);
    const bool fitted_run = (r.point - r.transfer).cwiseAbs().maxCoeff() > 0;
    for (const bool use_fit : {false, true}) {
      if (use_fit && !fitted_run) continue;
      const std::string label = name + (use_fit ? ", " + std::string(fit_method_name(base.fit.method)) : ", point");
      const Image frame = shade_gouraud(hits, r.mesh.triangles, vertex_radiance(use_fit ? r.transfer : r.point, light, 0.8));
      Image heat;
      const ImageError err = image_error(frame, reference, &heat, kHeatScale);
      const std::string file = std::string(name == "uniform" ? "frame_uniform" : "frame_adaptive") + (use_fit ? "_fit" : "_point");
      cli_write_image(c.out_dir + "/" + file + ".png", frame);
      cli_write_image(c.out_dir + "/" + file + "_error.png", heat);
      frames.push_back({label, std::to_string(r.mesh.num_faces()) + " triangles; image RMSE " + fmt(100 * err.rmse_relative, 3) + "%",
                        read_file_bytes(c.out_dir + "/" + file + ".png"), read_file_bytes(c.out_dir + "/" + file + "_error.png")});
    }
  }
  return frames;
}

// The adaptive asset of the frames in the viewer, with its error view against the source
// (reference rays: the reference frame's), as DIR/viewer.html and for the page's iframe.
std::string write_viewer(const CompareCli& c, const BakeOptions& base, const RayScene& source_scene,
                         const std::map<std::string, BakeResult>& keep) {
  const auto it = std::find_if(keep.begin(), keep.end(), [](const auto& run) { return run.first != "uniform"; });
  if (it == keep.end()) return "";
  const BakeResult& r = it->second;
  const Asset asset = make_asset(r.mesh, r.transfer, r.metadata, base.signal);
  TransferOptions t = base.transfer;
  t.rays = c.frame_rays;
  const ErrorView error = trace_error_view(asset, source_scene, t);
  ViewerPageOptions o;
  o.name = c.bake.input + " (" + it->first + ", " + std::to_string(r.mesh.num_faces()) + " triangles)";
  o.error = &error;
  const std::string page = viewer_page(asset, o);
  write_file_atomically(c.out_dir + "/viewer.html", page);
  return page;
}

// Plot series by name, in a fixed order: each gets its own colour and marker.
std::vector<PlotSeries> series_of(const std::vector<Row>& rows, bool by_time) {
  std::vector<PlotSeries> out;
  for (const Row& r : rows) {
    if (r.method == "none") continue;
    const std::string name = (r.method == "adaptive" || r.method == "simplify" || r.method == "auto" ? r.method + " " + r.estimate : r.method) +
                             (r.fit == "point" ? "" : " " + r.fit);
    auto it = std::find_if(out.begin(), out.end(), [&](const PlotSeries& s) { return s.name == name; });
    if (it == out.end()) it = out.insert(out.end(), PlotSeries{name, {}, true, 4, false});
    it->points.push_back({by_time ? r.seconds : double(r.triangles), r.rms});
  }
  return out;
}

void write_page(const CompareCli& c, const BakeOptions& base, size_t source_faces, const Reference& ref, const std::vector<Row>& rows,
                const std::vector<Frame>& frames, size_t frame_count, const std::string& pareto_html, const std::string& viewer) {
  const std::string& input = c.bake.input;
  std::ostringstream html;
  html << "<!doctype html><html><head><meta charset='utf-8'><title>prtsub compare: " << html_escape(input) << "</title>"
       << "<style>body{font-family:sans-serif;margin:24px;color:#222}table{border-collapse:collapse}td,th{padding:3px 10px;"
          "border-bottom:1px solid #ddd;text-align:right}th{background:#f4f4f4}td:first-child,td:nth-child(2){text-align:left}"
          "figure{display:inline-block;margin:6px}figcaption{font-size:12px;max-width:480px}"
          ".frames td{vertical-align:top;text-align:center;border:0;padding:4px}.frames img{display:block;max-width:100%;background:#222}"
          ".frames th{background:none;font-weight:600;text-align:center}iframe{border:1px solid #ccc;width:960px;height:600px;max-width:100%}</style></head><body>";
  html << "<h1>" << (rows.empty() ? "Rays and samples" : c.simplify ? "Refinement and simplification" : "Uniform against adaptive refinement")
       << "</h1><p>Input <code>"
       << html_escape(input) << "</code>, " << source_faces << " triangles. Order " << base.transfer.order << ", "
       << base.transfer.rays << " rays per vertex, seed " << base.transfer.seed
       << ". Error: surface RMS of ‖g − t<sub>ref</sub>‖ / ‖t<sub>unshadowed</sub>‖ at " << ref.points.rows()
       << " seeded area-stratified points, reference " << ref.rays << " rays (its own noise floor " << fmt(100 * ref.noise_floor, 3)
       << "%).";
  if (!rows.empty())
    html << " Vertex values: point sampled, and for uniform and the default estimate also " << fit_method_name(base.fit.method)
         << (base.fit.method == FitMethod::LeastSquares ? " (alpha " + fmt(base.fit.alpha, 3) + ", " + regularizer_name(base.fit.regularizer) + " regulariser)" : std::string())
         << " from " << fmt(base.samples.per_triangle, 3) << " surface samples per triangle with " << base.sample_rays
         << " rays each; a fitted run's time includes its samples and solve.";
  if (c.simplify)
    html << " Simplification rows: the input brought to 50%, 25% and 10% of its triangles (or as far as the guards allow), "
            "ranked by the transfer and by the geometry alone, fitted to samples of the source surface (alpha "
         << fmt(base.simplified_alpha, 3) << "); their points are located by closest point (docs/simplification.md). "
            "Rows 'auto': the same counts both ways (--refine auto: simplified to " << fmt(base.auto_share, 2)
         << " of the count where the transfer is smooth, then split where it varies, then " << base.auto_cycles
         << " further cycle(s) of collapsing a tenth and splitting back), located the same way.";
  html << "</p>";
  if (!rows.empty()) {
    html << "<h2>Error against triangles</h2>" << svg_loglog(series_of(rows, false), "triangles", "RMS error (%)");
    html << "<h2>Error against bake time</h2>" << svg_loglog(series_of(rows, true), "bake seconds", "RMS error (%)");
    html << "<h2>Runs</h2><table><tr><th>method</th><th>estimate</th><th>fit</th><th>triangles</th><th>vertices</th><th>RMS %</th>"
            "<th>p95 %</th><th>seconds</th></tr>";
    for (const Row& r : rows)
      html << "<tr><td>" << r.method << "</td><td>" << r.estimate << "</td><td>" << r.fit << "</td><td>" << r.triangles << "</td><td>"
           << r.vertices << "</td><td>" << fmt(r.rms) << "</td><td>" << fmt(r.p95) << "</td><td>" << fmt(r.seconds, 3) << "</td></tr>";
    html << "</table>";
  }
  html << pareto_html;
  if (!frames.empty()) {
    html << "<h2>Relit frames</h2><p>Frames at " << frame_count << " triangles under " << html_escape(c.lights[0])
         << (c.lights.size() > 1 ? " + " + html_escape(c.lights[1]) : "") << ", side by side with the per-pixel reference, which "
         << "computes transfer at every pixel (" << c.frame_rays << " rays). Below each frame its heat map, all on one scale: "
            "the per-pixel error as a share of the reference frame's mean radiance.</p>"
         << heat_colour_bar() << "<table class='frames'><tr>";
    for (const Frame& f : frames) html << "<th>" << html_escape(f.label) << "</th>";
    html << "</tr><tr>";
    for (const Frame& f : frames)
      html << "<td><img alt='" << html_escape(f.label) << "' src='data:image/png;base64," << base64_encode(f.png) << "'></td>";
    html << "</tr><tr>";
    for (const Frame& f : frames)
      html << "<td>" << (f.heat_png.empty() ? std::string() : "<img alt='error of " + html_escape(f.label) + "' src='data:image/png;base64," + base64_encode(f.heat_png) + "'>") << "</td>";
    html << "</tr><tr>";
    for (const Frame& f : frames) html << "<td style='font-size:12px'>" << html_escape(f.caption) << "</td>";
    html << "</tr></table>";
  }
  if (!viewer.empty())
    html << "<h2>The adaptive asset in the viewer</h2><p>Drag to turn the camera, shift-drag to turn the light; the panel "
            "changes the light and shows the error view (the asset against reference transfer on the source, under the light "
            "of the moment). The same page is <code>viewer.html</code> beside this report.</p><iframe title='viewer' srcdoc=\""
         << html_escape(viewer) << "\"></iframe>";
  const std::string tables = rows.empty() ? "pareto.csv and pareto.json"
                            : pareto_html.empty() ? "results.csv and results.json"
                                                  : "results.csv and results.json (refinement), pareto.csv and pareto.json (speed against error)";
  html << "<p style='font-size:12px;color:#666'>Made by <code>prtsub compare</code>; " << tables << " hold the same tables.</p></body></html>\n";
  write_file_atomically(c.out_dir + "/report.html", html.str());
}

}  // namespace

int cmd_compare(int argc, char** argv) {
  CompareCli c;
  ArgParser args("compare",
                 "Bakes INPUT with uniform refinement (OpenSubdiv, linear) and with adaptive refinement under every\n"
                 "estimate, evaluates each against one reference, and writes DIR/results.csv, DIR/results.json and\n"
                 "DIR/report.html (table, log-log plots of error against triangles and against time, relit frames).\n"
                 "With --pareto, also bakes the input under a grid of fixed ray and sample settings, the default and\n"
                 "--error targets, and shows each against the grid's best error at the same bake time.");
  c.add(args);
  if (!args.parse(argc, argv, 2)) return 0;
  if (c.budgets.empty() && !c.pareto && !c.simplify) throw UsageError("compare: missing --budgets T1,T2,... (or --pareto, --simplify)");
  if (c.out_dir.empty()) throw UsageError("compare: missing -o DIR");
  const std::vector<size_t> budgets = c.budgets.empty() ? std::vector<size_t>() : parse_budgets(c.budgets);
  const ParetoSpec pareto = c.pareto_spec();
  std::vector<EdgeEstimate> estimates;
  for (const std::string& e : split(c.estimates)) {
    try {
      estimates.push_back(parse_estimate(e));
    } catch (const InputError& err) {
      throw UsageError(std::string("--estimates: ") + err.what());
    }
  }
  if (c.lights.empty()) c.lights = {"sky", "sun:1,3,2"};
  parse_lights(c.lights, 1);  // usage mistakes now, not after the runs
  int fw = 0, fh = 0;
  parse_size(c.frame_size, "--frame-size", fw, fh);
  const BakeOptions base = resolve_bake_options(c.bake.options());
  require_fixed_order(base, "compare");
  {
    std::error_code ec;
    std::filesystem::create_directories(c.out_dir, ec);
    if (ec) throw IoError(c.out_dir + ": cannot create directory (" + ec.message() + ")");
  }
  check_writable(c.out_dir + "/report.html");
  if (!c.bake.report.empty()) check_writable(c.bake.report);

  const Stopwatch clock;
  const Mesh source = load_mesh(c.bake.input, c.bake.load);
  const RayScene source_scene(source.positions, position_triangles(source));
  ReferenceOptions ro;
  ro.points = static_cast<size_t>(c.eval_points);
  ro.rays = 8 * base.transfer.rays;
  ro.order = base.transfer.order;  // 1 for AO
  ro.threads = base.transfer.threads;
  // Runs baked with bounces are judged against bounced light; with auto each run would stop at
  // its own count, and one reference cannot hold them all.
  if (base.bounce.until_converged) throw UsageError("compare: --bounces auto stops each run at its own count; give a number");
  ro.bounces = base.bounce.bounces, ro.albedo = base.bounce.albedo;
  std::printf("prtsub compare: %s (%zu triangles), order %d, %d rays; reference %zu points x %d rays\n", c.bake.input.c_str(),
              source.num_faces(), base.transfer.order, base.transfer.rays, ro.points, ro.rays);
  std::fflush(stdout);
  const Reference ref = make_reference(source, source_scene, ro);
  std::printf("  reference noise floor %.3f%%\n", 100 * ref.noise_floor);

  size_t frame_count = 0;
  const std::vector<BakeOptions> plan =
      budgets.empty() && !c.simplify ? std::vector<BakeOptions>() : plan_runs(base, source.num_faces(), budgets, estimates, c.max_levels, c.simplify, frame_count);
  std::vector<Row> rows;
  std::map<std::string, BakeResult> keep;  // runs whose frames the page shows
  for (size_t i = 0; i < plan.size(); ++i) {
    const BakeOptions& s = plan[i];
    BakeResult r = bake(source, s);
    for (const Row& row : evaluate_run(s, r, ref)) {
      rows.push_back(row);
      std::printf("  [%zu/%zu] %-8s %-9s %-7s %8zu triangles: RMS %7.3f%%  p95 %7.3f%%  %.2f s\n", i + 1, plan.size(),
                  row.method.c_str(), row.estimate.c_str(), row.fit.c_str(), row.triangles, row.rms, row.p95, row.seconds);
      std::fflush(stdout);
    }
    if (!r.simplified && r.mesh.num_faces() == frame_count && (s.refine == Refinement::Uniform || s.estimate == BakeOptions{}.estimate)) {
      const std::string key = s.refine == Refinement::Uniform ? "uniform" : std::string("adaptive ") + estimate_name(s.estimate);
      keep.emplace(key, std::move(r));
    }
  }
  std::vector<ParetoRun> pareto_runs;
  const std::string pareto_html = c.pareto ? run_pareto(source, base, pareto, ref, c.out_dir, pareto_runs) : std::string();
  if (!plan.empty()) write_tables(c.out_dir, c.bake.input, base, ref, rows);
  const std::vector<Frame> frames = keep.empty() ? std::vector<Frame>() : render_frames(c, base, source, source_scene, keep);
  const std::string viewer = write_viewer(c, base, source_scene, keep);
  write_page(c, base, source.num_faces(), ref, rows, frames, frame_count, pareto_html, viewer);
  std::printf("  wrote %s/%sreport.html (%.1f s)\n", c.out_dir.c_str(),
              (std::string(plan.empty() ? "" : "results.csv, results.json, ") + (c.pareto ? "pareto.csv, pareto.json, " : "")).c_str(),
              clock.total());
  if (!c.bake.report.empty()) {
    Report r;
    r.set("command", "compare");
    r.set("input", c.bake.input);
    r.set("runs", rows.size());
    if (c.pareto) {
      r.set("pareto_runs", pareto_runs.size());
      // Each of the tool's own runs against the grid's front at its time: the worst ratio.
      double worst = 0;
      for (const ParetoRun& p : pareto_runs)
        if (p.series != "grid" && std::isfinite(p.front_rms)) worst = std::max(worst, p.rms / p.front_rms);
      r.set("pareto_worst_ratio_to_front", worst);
    }
    r.set("seconds_total", clock.total());
    r.set("noise_floor_percent", 100 * ref.noise_floor);
    r.write(c.bake.report);
  }
  return 0;
}

}  // namespace prtsub
