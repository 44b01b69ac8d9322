// compare --pareto: speed against error. The input baked under a grid of fixed settings (rays
// per vertex × surface samples per triangle × rays per sample), under the default, and under
// --error at several targets, every run judged by one reference; then each non-grid run set
// against the grid's best error at the same bake time.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "prtsub/prt/bake.h"
#include "prtsub/prt/evaluate.h"

namespace prtsub {

struct ParetoSpec {
  std::vector<int> vertex_rays{64, 256, 1024};
  std::vector<double> samples{0, 4, 16, 64};  //!< per triangle, every face by area; 0: point sampling
  std::vector<int> sample_rays{4, 16, 64};
  //! --error targets in percent; empty: 0.9, 0.8 and 0.7 of the default run's predicted error
  std::vector<double> targets;
};

struct ParetoRun {
  std::string series;  //!< "grid", "default" or "--error"
  std::string label;   //!< "R=256 S=16 Q=16", "default", "--error 1.2"
  BakeOptions options;
  double target = 0;   //!< --error runs: the target (percent)
  size_t vertices = 0;
  uint64_t rays = 0;
  double seconds = 0, rms = 0, p95 = 0, predicted = 0;
  //! Default and --error runs: the grid's front at this run's time (NaN when the run is faster
  //! than every grid run)
  double front_rms = 0;
};

//! The grid's settings on top of `base` (its order, seed, signal, fit and threads): point
//! sampling at each ray count, and the fit with area-allocated samples at every combination.
std::vector<ParetoRun> plan_pareto_grid(const BakeOptions& base, const ParetoSpec& spec);

//! The non-dominated (seconds, error) points, ascending in time and strictly descending in error.
std::vector<std::pair<double, double>> pareto_front(std::vector<std::pair<double, double>> points);

//! The front's error at `seconds`: interpolated linearly in log time and log error between the
//! front points around it, the last point's beyond it, NaN before the first.
double front_error_at(const std::vector<std::pair<double, double>>& front, double seconds);

//! Runs the grid, the default and the targets on `source`, prints a line per run, writes
//! DIR/pareto.csv and DIR/pareto.json, and returns the report's HTML section.
std::string run_pareto(const Mesh& source, const BakeOptions& base, const ParetoSpec& spec, const Reference& reference,
                       const std::string& dir, std::vector<ParetoRun>& runs);

}  // namespace prtsub
