// Which settings buy the most accuracy per second. Every run bakes the same input with the same
// order and seed and is judged by one fixed reference, so errors differ only by the settings.
// The grid is the baseline a user could tune by hand: R rays per vertex, then either nothing
// (point sampling) or S samples per triangle on every face by area, each with Q rays, fitted by
// least squares. Its Pareto front (no other grid run both faster and more accurate) is what a
// perfect hand tuning could reach at each time; the default and --error runs are set against
// it at their own bake time, interpolated between front points in log-log (errors fall about
// as a power of time, so straight lines there are the fair reading between two settings).
#include "cli/pareto.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "cli/escape.h"
#include "cli/plot.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/output_file.h"

namespace prtsub {
namespace {

// An empty cell for what is not a number (a grid run's front).
std::string fmt(double v, int digits = 4) { return std::isfinite(v) ? format_number(v, digits) : std::string(); }

std::string fixed(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", v);
  return b;
}

void bake_and_judge(const Mesh& source, const Reference& reference, ParetoRun& run) {
  const BakeResult r = bake(source, run.options);
  const EvalResult e = evaluate(reference, vertex_positions(r.mesh), r.mesh.triangles, r.mesh.source_face, r.transfer);
  run.vertices = r.mesh.num_vertices();
  run.rays = r.rays;
  run.seconds = r.seconds_total;
  run.rms = e.rms_percent, run.p95 = e.p95_percent;
  run.predicted = r.predicted.percent;
}

void write_results(const std::string& dir, const std::vector<ParetoRun>& runs) {
  std::ostringstream csv, json;
  csv << "series,label,vertex_rays,samples_per_triangle,sample_rays,target_percent,vertices,rays,seconds,rms_percent,p95_percent,"
         "predicted_percent,front_rms_percent\n";
  json << "{\n  \"runs\": [\n";
  for (size_t i = 0; i < runs.size(); ++i) {
    const ParetoRun& r = runs[i];
    const bool fixed = r.series == "grid";
    const std::string samples = fixed ? (r.options.fit.method == FitMethod::Point ? "0" : fmt(r.options.samples.per_triangle)) : "";
    const std::string qrays = fixed && r.options.fit.method != FitMethod::Point ? std::to_string(r.options.sample_rays) : "";
    csv << r.series << "," << r.label << "," << r.options.transfer.rays << "," << samples << "," << qrays << "," << (r.target > 0 ? fmt(r.target) : "")
        << "," << r.vertices << "," << r.rays << "," << fmt(r.seconds, 6) << "," << fmt(r.rms, 6) << "," << fmt(r.p95, 6) << ","
        << (r.predicted > 0 ? fmt(r.predicted, 6) : "") << "," << fmt(r.front_rms, 6) << "\n";
    auto number = [](double v) { return std::isfinite(v) ? fmt(v, 6) : std::string("null"); };
    json << "    {\"series\": " << json_quote(r.series) << ", \"label\": " << json_quote(r.label) << ", \"vertex_rays\": " << r.options.transfer.rays
         << ", \"samples_per_triangle\": " << (samples.empty() ? "null" : samples) << ", \"sample_rays\": " << (qrays.empty() ? "null" : qrays)
         << ", \"target_percent\": " << (r.target > 0 ? fmt(r.target) : "null") << ", \"vertices\": " << r.vertices << ", \"rays\": " << r.rays
         << ", \"seconds\": " << number(r.seconds) << ", \"rms_percent\": " << number(r.rms) << ", \"p95_percent\": " << number(r.p95)
         << ", \"predicted_percent\": " << (r.predicted > 0 ? number(r.predicted) : "null")
         << ", \"front_rms_percent\": " << (r.series == "grid" ? "null" : number(r.front_rms)) << "}" << (i + 1 < runs.size() ? ",\n" : "\n");
  }
  json << "  ]\n}\n";
  write_file_atomically(dir + "/pareto.csv", csv.str());
  write_file_atomically(dir + "/pareto.json", json.str());
}

std::string html_section(const std::vector<ParetoRun>& runs, const std::vector<std::pair<double, double>>& front) {
  std::vector<PlotSeries> series;
  PlotSeries grid{"grid of fixed settings", {}, false, 3, true}, edge{"the grid's front", front, true, 3, false};
  for (const ParetoRun& r : runs)
    if (r.series == "grid") grid.points.push_back({r.seconds, r.rms});
  series.push_back(grid);
  series.push_back(edge);
  // The axis stops at twice the worst of the tool's own runs: point-sampled grid runs can be
  // several times worse and would squash the runs that matter onto one line.
  double worst = 0;
  for (const ParetoRun& r : runs)
    if (r.series != "grid") {
      series.push_back({r.label, {{r.seconds, r.rms}}, false, 6, false});
      if (std::isfinite(r.rms)) worst = std::max(worst, r.rms);
    }
  std::ostringstream html;
  html << "<h2>Speed against error</h2><p>Eval error against bake seconds. Grey: every fixed setting of the grid (R rays per vertex; "
          "S samples per triangle on every face by area with Q rays each, fitted, or none: point sampling). The line joins the grid's "
          "front: no grid run is both faster and more accurate. Each coloured marker is one run of the tool's own choices; the table "
          "sets it against the front at its own time (log-log interpolation).</p>"
       << svg_loglog(series, "bake seconds", "RMS error (%)", 760, 440, 2 * worst);
  html << "<table><tr><th>run</th><th>seconds</th><th>rays</th><th>RMS %</th><th>predicted %</th><th>front's RMS % at its time</th>"
          "<th>run / front</th></tr>";
  for (const ParetoRun& r : runs) {
    if (r.series == "grid") continue;
    html << "<tr><td>" << html_escape(r.label) << "</td><td>" << fmt(r.seconds, 3) << "</td><td>" << r.rays << "</td><td>" << fmt(r.rms)
         << "</td><td>" << fmt(r.predicted) << "</td><td>" << (std::isfinite(r.front_rms) ? fmt(r.front_rms) : "faster than every grid run")
         << "</td><td>" << (std::isfinite(r.front_rms) ? fixed(r.rms / r.front_rms) : "") << "</td></tr>";
  }
  html << "</table><details><summary>Every grid run</summary><table><tr><th>setting</th><th>seconds</th><th>rays</th><th>RMS %</th>"
          "<th>p95 %</th></tr>";
  for (const ParetoRun& r : runs)
    if (r.series == "grid")
      html << "<tr><td>" << html_escape(r.label) << "</td><td>" << fmt(r.seconds, 3) << "</td><td>" << r.rays << "</td><td>" << fmt(r.rms)
           << "</td><td>" << fmt(r.p95) << "</td></tr>";
  html << "</table></details>";
  return html.str();
}

}  // namespace

std::vector<ParetoRun> plan_pareto_grid(const BakeOptions& base, const ParetoSpec& spec) {
  std::vector<ParetoRun> plan;
  for (int rays : spec.vertex_rays) {
    for (double s : spec.samples) {
      ParetoRun run;
      run.series = "grid";
      run.options = base;
      run.options.transfer.rays = rays;
      run.options.target_error = 0;
      if (s <= 0) {
        run.options.fit.method = FitMethod::Point;
        run.label = "R=" + std::to_string(rays) + " point";
        plan.push_back(run);
        continue;
      }
      if (run.options.fit.method == FitMethod::Point) run.options.fit.method = FitMethod::LeastSquares;
      run.options.allocation = SampleAllocation::Area;
      run.options.samples.per_triangle = s, run.options.samples.density = 0;
      for (int q : spec.sample_rays) {
        run.options.sample_rays = q;
        run.label = "R=" + std::to_string(rays) + " S=" + fmt(s) + " Q=" + std::to_string(q);
        plan.push_back(run);
      }
    }
  }
  return plan;
}

std::vector<std::pair<double, double>> pareto_front(std::vector<std::pair<double, double>> points) {
  std::sort(points.begin(), points.end());
  std::vector<std::pair<double, double>> front;
  for (auto p : points)
    if (std::isfinite(p.first) && std::isfinite(p.second) && (front.empty() || p.second < front.back().second)) {
      if (!front.empty() && front.back().first == p.first) front.pop_back();  // as fast, more accurate
      front.push_back(p);
    }
  return front;
}

double front_error_at(const std::vector<std::pair<double, double>>& front, double seconds) {
  if (front.empty() || !(seconds >= front.front().first)) return std::numeric_limits<double>::quiet_NaN();
  for (size_t i = 1; i < front.size(); ++i) {
    const auto [t0, e0] = front[i - 1];
    const auto [t1, e1] = front[i];
    if (seconds > t1) continue;
    if (!(t0 > 0 && e0 > 0 && e1 > 0)) return e0;
    const double u = std::log(seconds / t0) / std::log(t1 / t0);
    return std::exp(std::log(e0) + u * (std::log(e1) - std::log(e0)));
  }
  return front.back().second;
}

std::string run_pareto(const Mesh& source, const BakeOptions& base, const ParetoSpec& spec, const Reference& reference,
                       const std::string& dir, std::vector<ParetoRun>& runs) {
  runs = plan_pareto_grid(base, spec);
  ParetoRun d;
  d.series = "default", d.label = "default", d.options = base;
  runs.insert(runs.begin(), d);
  // The default targets come from the default run's prediction, which only a pilot bake makes.
  const bool predicts = base.fit.method != FitMethod::Point && base.allocation == SampleAllocation::Pilot;
  const size_t total_guess = runs.size() + (!spec.targets.empty() ? spec.targets.size() : predicts ? 3 : 0);
  auto report = [&](size_t i) {
    const ParetoRun& r = runs[i];
    std::printf("  [%zu/%zu] %-22s %10.3f s  %14llu rays  RMS %7.3f%%\n", i + 1, total_guess, r.label.c_str(), r.seconds,
                static_cast<unsigned long long>(r.rays), r.rms);
    std::fflush(stdout);
  };
  bake_and_judge(source, reference, runs[0]);
  report(0);
  std::vector<double> targets = spec.targets;
  if (targets.empty() && runs[0].predicted > 0)
    for (double f : {0.9, 0.8, 0.7}) targets.push_back(std::round(f * runs[0].predicted * 1000) / 1000);
  for (size_t k = 0; k < targets.size(); ++k) {
    ParetoRun e;
    e.series = "--error", e.label = "--error " + fmt(targets[k]), e.options = base, e.target = targets[k];
    e.options.target_error = targets[k];
    runs.insert(runs.begin() + 1 + static_cast<std::ptrdiff_t>(k), e);
  }
  for (size_t i = 1; i < runs.size(); ++i) {
    bake_and_judge(source, reference, runs[i]);
    report(i);
  }
  std::vector<std::pair<double, double>> grid;
  for (const ParetoRun& r : runs)
    if (r.series == "grid") grid.push_back({r.seconds, r.rms});
  const auto front = pareto_front(grid);
  for (ParetoRun& r : runs) r.front_rms = r.series == "grid" ? std::numeric_limits<double>::quiet_NaN() : front_error_at(front, r.seconds);
  write_results(dir, runs);
  return html_section(runs, front);
}

}  // namespace prtsub
