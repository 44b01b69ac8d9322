// Each series gets colour i mod 10 and marker i mod 6 in the order given; series that are a
// backdrop (muted) are drawn first in grey so the named ones stay on top.
#include "cli/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "cli/escape.h"

namespace prtsub {
std::string format_number(double v, int digits) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

namespace {

std::string num(double v, int digits = 4) { return format_number(v, digits); }

// Tick labels: whole numbers in full up to ten million (1500, not 1.5e+03).
std::string tick(double v) {
  if (v >= 1000 && v < 1e7) {
    char b[32];
    std::snprintf(b, sizeof b, "%.0f", v);
    return b;
  }
  return num(v, 3);
}

// A marker of shape `k` centred at (x, y) with radius r.
std::string marker(int k, double x, double y, double r, const std::string& colour) {
  std::ostringstream o;
  const std::string fill = "fill='" + colour + "' stroke='" + colour + "'";
  switch (k % 6) {
    case 0: o << "<circle cx='" << num(x) << "' cy='" << num(y) << "' r='" << num(r) << "' " << fill << "/>"; break;
    case 1: o << "<rect x='" << num(x - r) << "' y='" << num(y - r) << "' width='" << num(2 * r) << "' height='" << num(2 * r) << "' " << fill << "/>"; break;
    case 2:
      o << "<polygon points='" << num(x) << "," << num(y - 1.2 * r) << " " << num(x + 1.1 * r) << "," << num(y + 0.8 * r) << " " << num(x - 1.1 * r)
        << "," << num(y + 0.8 * r) << "' " << fill << "/>";
      break;
    case 3:
      o << "<polygon points='" << num(x) << "," << num(y - 1.3 * r) << " " << num(x + 1.3 * r) << "," << num(y) << " " << num(x) << ","
        << num(y + 1.3 * r) << " " << num(x - 1.3 * r) << "," << num(y) << "' " << fill << "/>";
      break;
    case 4:
      o << "<path d='M" << num(x - r) << " " << num(y - r) << "L" << num(x + r) << " " << num(y + r) << "M" << num(x - r) << " " << num(y + r)
        << "L" << num(x + r) << " " << num(y - r) << "' stroke='" << colour << "' stroke-width='2.2' fill='none'/>";
      break;
    default:
      o << "<circle cx='" << num(x) << "' cy='" << num(y) << "' r='" << num(r) << "' fill='white' stroke='" << colour
        << "' stroke-width='2'/>";
  }
  return o.str();
}

}  // namespace

std::string svg_loglog(const std::vector<PlotSeries>& series, const std::string& xlabel, const std::string& ylabel, int width, int height,
                       double y_limit) {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  size_t above = 0;
  const bool limited = y_limit > 0 && std::isfinite(y_limit);
  for (const PlotSeries& s : series)
    for (auto [x, y] : s.points)
      if (x > 0 && y > 0 && std::isfinite(x) && std::isfinite(y)) {
        x0 = std::min(x0, x), x1 = std::max(x1, x);
        if (limited && y > y_limit) {
          ++above;
          continue;
        }
        y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
  if (x0 > x1) return "<p>(no data)</p>";
  if (above > 0) y1 = y_limit, y0 = std::min(y0, y_limit);
  // 6% of the log range on each side (at least a tenth of a decade in all), so no point sits on the frame.
  auto pad = [](double& lo, double& hi) {
    const double span = std::max(std::log10(hi) - std::log10(lo), 0.1 / 0.88);
    const double mid = (std::log10(hi) + std::log10(lo)) / 2;
    lo = std::pow(10, mid - 0.56 * span), hi = std::pow(10, mid + 0.56 * span);
  };
  pad(x0, x1), pad(y0, y1);
  const double W = width, H = height, L = 70, R = 230, T = 20, B = 50;
  auto px = [&](double x) { return L + (std::log10(x) - std::log10(x0)) / (std::log10(x1) - std::log10(x0)) * (W - L - R); };
  auto py = [&](double y) { return H - B - (std::log10(y) - std::log10(y0)) / (std::log10(y1) - std::log10(y0)) * (H - T - B); };
  // Tableau 10: distinct in hue and, for most pairs, in lightness.
  static const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                  "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#222222"};
  std::ostringstream o;
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "' font-family='sans-serif' font-size='13'>";
  o << "<rect x='" << L << "' y='" << T << "' width='" << W - L - R << "' height='" << H - T - B << "' fill='none' stroke='#999'/>";
  // Gridlines at 1, 2, 5 per decade; finer where the axis spans less than a decade and a half.
  auto mantissas = [](double lo, double hi) {
    return std::log10(hi / lo) < 1.5 ? std::vector<double>{1, 1.5, 2, 3, 4, 5, 6, 7, 8, 9} : std::vector<double>{1, 2, 5};
  };
  double last_label_right = -1e300, last_label_top = 1e300;
  for (int e = static_cast<int>(std::floor(std::log10(x0))); e <= std::ceil(std::log10(x1)); ++e)
    for (double m : mantissas(x0, x1)) {
      const double x = m * std::pow(10, e);
      if (x < x0 || x > x1) continue;
      o << "<line x1='" << num(px(x)) << "' x2='" << num(px(x)) << "' y1='" << T << "' y2='" << H - B << "' stroke='#e4e4e4'/>";
      // A label only where it clears the last one (about 8 px a character at this size): the fine
      // gridlines crowd towards the top of a decade (7000 8000 9000 10000 ran together).
      const std::string label = tick(x);
      const double half = 4.0 * double(label.size()) + 4;
      if (px(x) - half < last_label_right) continue;
      last_label_right = px(x) + half;
      o << "<text x='" << num(px(x)) << "' y='" << H - B + 16 << "' text-anchor='middle'>" << label << "</text>";
    }
  for (int e = static_cast<int>(std::floor(std::log10(y0))); e <= std::ceil(std::log10(y1)); ++e)
    for (double m : mantissas(y0, y1)) {
      const double y = m * std::pow(10, e);
      if (y < y0 || y > y1) continue;
      o << "<line x1='" << L << "' x2='" << W - R << "' y1='" << num(py(y)) << "' y2='" << num(py(y)) << "' stroke='#e4e4e4'/>";
      if (py(y) + 15 > last_label_top) continue;  // the same on y: a label's height apart
      last_label_top = py(y);
      o << "<text x='" << L - 5 << "' y='" << num(py(y) + 4) << "' text-anchor='end'>" << tick(y) << "</text>";
    }
  o << "<text x='" << (L + W - R) / 2 << "' y='" << H - 12 << "' text-anchor='middle'>" << html_escape(xlabel) << "</text>";
  if (above > 0)  // two lines: one would run past the legend's column (230 px)
    o << "<text x='" << W - R + 12 << "' y='" << H - 26 << "' font-size='11'>" << above << (above == 1 ? " point" : " points") << " above "
      << tick(y_limit) << ":</text><text x='" << W - R + 12 << "' y='" << H - 12 << "' font-size='11'>\u25B2 on the top edge</text>";
  o << "<text transform='rotate(-90)' x='" << -(T + H - B) / 2 << "' y='18' text-anchor='middle'>" << html_escape(ylabel) << "</text>";
  std::vector<size_t> order(series.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return series[a].muted > series[b].muted; });
  int named = 0, legend = 0;
  std::vector<int> style(series.size(), -1);
  for (size_t i = 0; i < series.size(); ++i)
    if (!series[i].muted) style[i] = named++;
  for (size_t i : order) {
    const PlotSeries& s = series[i];
    const std::string col = s.muted ? "#b0b0b0" : colours[style[i] % 10];
    const int shape = s.muted ? 0 : style[i] % 6;
    std::vector<std::pair<double, double>> pts;
    for (auto p : s.points)
      if (p.first > 0 && p.second > 0 && std::isfinite(p.first) && std::isfinite(p.second)) pts.push_back(p);
    std::sort(pts.begin(), pts.end());
    // Above the limit: on the top edge (the frame's top is y1, padded), as an upward triangle.
    auto ty = [&](double y) { return above > 0 && y > y_limit ? double(T) : py(y); };
    if (s.line && pts.size() > 1) {
      o << "<polyline fill='none' stroke='" << col << "' stroke-width='" << (s.muted ? 1 : 1.8) << "' points='";
      for (auto [x, y] : pts) o << num(px(x)) << "," << num(ty(y)) << " ";
      o << "'/>";
    }
    for (auto [x, y] : pts) {
      const double r = s.muted ? std::min(s.marker, 2.5) : s.marker;
      o << (above > 0 && y > y_limit ? marker(2, px(x), T + 1.2 * r, r, col) : marker(shape, px(x), py(y), r, col));
    }
    const double ly = T + 14 + 20 * legend++;
    if (s.line) o << "<line x1='" << W - R + 12 << "' x2='" << W - R + 40 << "' y1='" << ly << "' y2='" << ly << "' stroke='" << col << "' stroke-width='2'/>";
    o << marker(shape, W - R + 26, ly, s.muted ? 2.5 : 4, col);
    o << "<text x='" << W - R + 46 << "' y='" << ly + 4 << "'>" << html_escape(s.name) << "</text>";
  }
  o << "</svg>";
  return o.str();
}

}  // namespace prtsub
