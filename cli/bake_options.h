// Options and progress shared by the commands that bake (bake, compare, eval --fits).
#pragma once

#include <memory>
#include <string>

#include "cli/args.h"
#include "cli/pipeline.h"
#include "cli/progress.h"
#include "cli/report.h"

namespace prtsub {

//! The signal and fit options, declared once for every command that bakes.
struct FitCli {
  std::string signal = "transfer", fit = "lsq", regularizer = "edge", mass = "analytic", solver = "auto";
  int min_samples = 1;
  bool no_control_variate = false;
  BakeSettings settings;  //!< holds the numeric options' values and defaults
  void add(ArgParser& args);
  //! Copies the options into b (after b.transfer is set: the sample seed derives from it).
  //! \throw UsageError for a bad name
  void apply(BakeSettings& b) const;
};

//! One progress line per pipeline stage.
class StageProgress {
 public:
  StageProgress();
  ~StageProgress();
  BakeProgress callbacks();
  void finish();

 private:
  bool enabled_;
  std::unique_ptr<Progress> current_;
};

//! The fit's report keys (fit, samples, timings, solve memory, ...).
void add_fit_report(Report& r, const BakeResult& res, const BakeSettings& b);

}  // namespace prtsub
