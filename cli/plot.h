// Log-log plots for the tool's HTML pages, as inline SVG: one distinct colour and marker per
// series (ten colours, six markers, so up to thirty series never share both), a legend beside
// the frame, and decade gridlines labelled 1, 2, 5.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace prtsub {

struct PlotSeries {
  std::string name;
  std::vector<std::pair<double, double>> points;  //!< (x, y); points with x or y ≤ 0 are left out
  bool line = true;     //!< join the points in x order; false: markers only
  double marker = 4;    //!< marker radius in pixels
  bool muted = false;   //!< grey and small: a backdrop (a grid of runs) behind the named series
};

//! `v` with `digits` significant digits (printf's %g): the numbers of every page and table.
std::string format_number(double v, int digits = 4);

//! A log-log plot of `series` in a `width` × `height` SVG element; "<p>(no data)</p>" when no
//! point is positive.
//! `y_limit` > 0: the y axis stops there, and points above it are drawn on the top edge as
//! upward triangles (lines flattened there too), counted in a note under the frame, so that a few
//! far worse runs do not squash the ones that matter onto one line.
std::string svg_loglog(const std::vector<PlotSeries>& series, const std::string& xlabel, const std::string& ylabel, int width = 760,
                       int height = 440, double y_limit = 0);

}  // namespace prtsub
