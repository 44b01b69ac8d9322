// compare --pareto: the grid it runs, the front it draws and how it reads the front between
// runs; and the plots every page uses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <sstream>

#include "cli/commands.h"
#include "cli/pareto.h"
#include "cli/plot.h"
#include "cli_helpers.h"
#include "helpers.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

TEST(Pareto, TheFrontKeepsExactlyTheRunsNoOtherBeatsOnTimeAndError) {
  // (seconds, error): (2, 9) is beaten by (1, 8); (3, 8) ties (1, 8)'s error later; (4, 3) and
  // (4, 2) share a time, and only the better stays.
  const auto front = pareto_front({{2, 9}, {1, 8}, {3, 8}, {5, 4}, {4, 3}, {4, 2}, {6, 2}, {7, 1}, {0.5, 20}});
  const std::vector<std::pair<double, double>> want{{0.5, 20}, {1, 8}, {4, 2}, {7, 1}};
  EXPECT_EQ(front, want);
  EXPECT_TRUE(pareto_front({}).empty());
  // A NaN time or error is not a run.
  EXPECT_EQ(pareto_front({{1, std::nan("")}, {std::nan(""), 1}, {2, 3}}), (std::vector<std::pair<double, double>>{{2, 3}}));
}

TEST(Pareto, TheFrontIsReadBetweenItsRunsAsAPowerOfTime) {
  const std::vector<std::pair<double, double>> front{{1, 10}, {4, 5}, {16, 4}};
  // Halfway between 1 s and 4 s in log time: halfway between 10 and 5 in log error.
  EXPECT_NEAR(front_error_at(front, 2), 10 * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(front_error_at(front, 8), 5 * std::sqrt(0.8), 1e-12);
  EXPECT_DOUBLE_EQ(front_error_at(front, 1), 10);
  EXPECT_DOUBLE_EQ(front_error_at(front, 4), 5);
  EXPECT_DOUBLE_EQ(front_error_at(front, 100), 4);  // slower than every run: the best there is
  EXPECT_TRUE(std::isnan(front_error_at(front, 0.5)));  // faster than every run: nothing to compare
  EXPECT_TRUE(std::isnan(front_error_at({}, 1)));
}

TEST(Pareto, TheGridIsPointSamplingAtEveryRayCountAndTheFitAtEveryCombination) {
  BakeOptions base;
  base.transfer.order = 3;
  base.transfer.seed = 9;
  ParetoSpec spec;
  spec.vertex_rays = {32, 128};
  spec.samples = {0, 2, 8};
  spec.sample_rays = {4, 16, 64};
  const std::vector<ParetoRun> plan = plan_pareto_grid(base, spec);
  ASSERT_EQ(plan.size(), 2u * (1 + 2 * 3));
  std::set<std::string> labels;
  size_t point = 0;
  for (const ParetoRun& r : plan) {
    labels.insert(r.label);
    EXPECT_EQ(r.series, "grid");
    EXPECT_EQ(r.options.transfer.order, 3);
    EXPECT_EQ(r.options.transfer.seed, 9u);
    EXPECT_EQ(r.options.target_error, 0);
    if (r.options.fit.method == FitMethod::Point) {
      ++point;
      continue;
    }
    EXPECT_EQ(r.options.fit.method, FitMethod::LeastSquares);
    EXPECT_EQ(r.options.allocation, SampleAllocation::Area);  // fixed settings: every face, by area
    EXPECT_EQ(r.options.samples.density, 0);
  }
  EXPECT_EQ(point, 2u);
  EXPECT_EQ(labels.size(), plan.size());
  EXPECT_EQ(plan[0].label, "R=32 point");
  EXPECT_EQ(plan[1].label, "R=32 S=2 Q=4");
  EXPECT_EQ(plan[1].options.samples.per_triangle, 2);
  EXPECT_EQ(plan[1].options.sample_rays, 4);
  EXPECT_EQ(plan.back().label, "R=128 S=8 Q=64");
  EXPECT_EQ(plan.back().options.transfer.rays, 128);
}

TEST(Plot, EveryNamedSeriesHasItsOwnColourAndMarkerAndALegendLine) {
  std::vector<PlotSeries> series;
  series.push_back({"backdrop", {{1, 1}, {2, 3}}, false, 3, true});
  for (int i = 0; i < 12; ++i) series.push_back({"s" + std::to_string(i), {{1.0 + i, 2.0 + i}}, i % 2 == 0, 4, false});
  const std::string svg = svg_loglog(series, "x <s>", "y");
  for (const char* colour : {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#222222"})
    EXPECT_NE(svg.find(colour), std::string::npos) << colour;
  EXPECT_NE(svg.find("#b0b0b0"), std::string::npos);  // the backdrop is grey
  for (int i = 0; i < 12; ++i) EXPECT_NE(svg.find(">s" + std::to_string(i) + "</text>"), std::string::npos) << i;
  EXPECT_NE(svg.find("x &lt;s&gt;"), std::string::npos);
  // Series 0 and 10 share a colour (ten of them), not a marker: 10 mod 6 is a square, 0 a circle.
  EXPECT_NE(svg.find("<rect x='"), std::string::npos);
  EXPECT_EQ(svg_loglog({{"empty", {{0, 1}, {-1, 2}}}}, "x", "y"), "<p>(no data)</p>");
}

TEST(Plot, PointsAboveTheLimitSitOnTheTopEdgeAndAreCounted) {
  // Two runs near 7% and one at 45%: limited at 14, the axis spans 7–14 (padded), the 45% point
  // is an upward triangle on the frame's top (y = 20), and a note counts it.
  const std::vector<PlotSeries> series{{"runs", {{1, 7}, {2, 7.2}, {0.5, 45}}, true, 4, false}};
  const std::string limited = svg_loglog(series, "s", "e", 760, 440, 14), full = svg_loglog(series, "s", "e");
  EXPECT_NE(limited.find("1 point above 14"), std::string::npos);
  EXPECT_EQ(full.find("above"), std::string::npos);
  // No y tick label above the limit: 20 and 50 are labelled only without it.
  EXPECT_EQ(limited.find(">20</text>"), std::string::npos);
  EXPECT_NE(full.find(">20</text>"), std::string::npos);
  // The two near 7% are 2.7 times further apart on the limited axis.
  auto ys = [](const std::string& svg) {
    std::vector<double> out;
    for (size_t at = svg.find("<circle cx='"); at != std::string::npos; at = svg.find("<circle cx='", at + 1))
      out.push_back(std::stod(svg.substr(svg.find("cy='", at) + 4)));
    return out;
  };
  // Markers in x order: the full plot's first circle is the 45% run, the limited plot's a triangle.
  const std::vector<double> a = ys(limited), b = ys(full);
  ASSERT_GE(a.size(), 2u);
  ASSERT_GE(b.size(), 3u);
  EXPECT_GT(std::abs(a[0] - a[1]), 2.5 * std::abs(b[1] - b[2]));  // the spans: log(45/7) against log(14/7)
  // The clipped point is a triangle whose apex is on the frame's top edge's band.
  const size_t tri = limited.find("<polygon points='");
  ASSERT_NE(tri, std::string::npos);
  const std::string pts = limited.substr(tri + 17, 40);
  EXPECT_NEAR(std::stod(pts.substr(pts.find(',') + 1)), 20.0, 1.0);
}

TEST(Plot, TickLabelsNeverRunTogether) {
  // 1,500 to 20,000 triangles: a decade and a bit, so gridlines at every mantissa 1..9, which
  // crowd towards 10,000. Each x label sits at least its own width (8 px a character) from the last.
  const std::string svg = svg_loglog({{"s", {{1500, 2}, {20000, 30}}}}, "triangles", "RMS");
  std::vector<std::pair<double, size_t>> labels;  // (x, characters) of the x axis's labels
  for (size_t at = svg.find("text-anchor='middle'>"); at != std::string::npos; at = svg.find("text-anchor='middle'>", at + 1)) {
    const size_t x = svg.rfind("<text x='", at) + 9, end = svg.find("</text>", at);
    const std::string text = svg.substr(at + 21, end - at - 21);
    if (text.empty() || !std::isdigit(static_cast<unsigned char>(text[0]))) continue;  // the axis titles
    labels.push_back({std::stod(svg.substr(x)), text.size()});
  }
  ASSERT_GE(labels.size(), 5u);
  for (size_t i = 1; i < labels.size(); ++i)
    EXPECT_GE(labels[i].first - labels[i - 1].first, 4.0 * double(labels[i].second + labels[i - 1].second)) << i;
}

int run(std::vector<std::string> args) { return test::run_prtsub(std::move(args)); }

// The number after "key": in a flat JSON report, or after the n-th comma of a CSV row.
double json_number(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\": ");
  return at == std::string::npos ? std::nan("") : std::atof(json.c_str() + at + key.size() + 4);
}

TEST(ComparePareto, WritesEveryRunAndSetsTheToolsOwnAgainstTheGridsFront) {
  test::TempDir dir;
  const std::string in = dir.path("m.obj");
  test::write_obj(in, test::merge(test::icosphere(1), test::quad(3.0, -1.0, true)));
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"compare", in, "--pareto", "--grid-rays", "8,32", "--grid-samples", "0,2", "--grid-sample-rays", "4,8", "--targets",
                 "5,3", "--rays", "16", "--eval-points", "300", "-o", dir.path("p"), "--report", dir.path("p.json")}),
            0);
  testing::internal::GetCapturedStdout();
  const std::string csv = read_file_bytes(dir.path("p/pareto.csv")), html = read_file_bytes(dir.path("p/report.html"));
  // The default, two targets, and 2 ray counts × (point + 1 sample count × 2 sample ray counts).
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 1 + 2 + 2 * 3);
  EXPECT_NE(csv.find("\ndefault,default,16,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\n--error,--error 3,16,,,3,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\ngrid,R=32 S=2 Q=8,32,2,8,,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\ngrid,R=8 point,8,0,,,"), std::string::npos) << csv;
  EXPECT_NE(html.find("<h2>Speed against error</h2>"), std::string::npos);
  EXPECT_NE(html.find("the grid&#39;s front"), std::string::npos);
  EXPECT_EQ(html.find("Uniform against adaptive"), std::string::npos);  // no --budgets: no refinement runs
  const std::string report = read_file_bytes(dir.path("p.json"));
  EXPECT_NE(report.find("\"pareto_runs\": 9"), std::string::npos) << report;
  EXPECT_NE(report.find("\"pareto_worst_ratio_to_front\""), std::string::npos);
  // The row of a grid run is what bake and eval give by hand with the same settings and the
  // same reference (compare's: 8 × --rays, eval's seeded points).
  const size_t row = csv.find("\ngrid,R=32 S=2 Q=8,");
  ASSERT_NE(row, std::string::npos);
  std::vector<std::string> cells;
  {
    std::stringstream line(csv.substr(row + 1, csv.find('\n', row + 1) - row - 1));
    for (std::string cell; std::getline(line, cell, ',');) cells.push_back(cell);
  }
  ASSERT_EQ(cells.size(), 12u);  // a grid row has no front: its last cell is empty
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({"bake", in, "--rays", "32", "--sample-allocation", "area", "--samples-per-triangle", "2", "--sample-rays", "8", "-o",
                 dir.path("g.ply"), "--report", dir.path("b.json")}),
            0);
  ASSERT_EQ(run({"eval", dir.path("g.ply"), "--source", in, "--points", "300", "--rays", "128", "--report", dir.path("g.json")}), 0);
  testing::internal::GetCapturedStdout();
  const double rms = json_number(read_file_bytes(dir.path("g.json")), "rms_percent");
  EXPECT_NEAR(std::atof(cells[9].c_str()), rms, 1e-5 * rms) << csv;
  EXPECT_EQ(cells[7], std::to_string(static_cast<uint64_t>(json_number(read_file_bytes(dir.path("b.json")), "rays"))));
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"compare", in, "-o", dir.path("q")}), 2);  // neither --budgets nor --pareto
  EXPECT_EQ(run({"compare", in, "--pareto", "--grid-rays", "8,x", "-o", dir.path("q")}), 2);
  EXPECT_EQ(run({"compare", in, "--pareto", "--grid-sample-rays", "1", "-o", dir.path("q")}), 2);
  EXPECT_EQ(run({"compare", in, "--pareto", "--targets", "-1", "-o", dir.path("q")}), 2);
  testing::internal::GetCapturedStderr();
}

}  // namespace
}  // namespace prtsub
