// Options shared by the commands, declared once each. Every option binds straight to a field of
// the library's option structs, so each default is the struct's, written once.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cli/args.h"
#include "cli/progress.h"
#include "prtsub/prt/bake.h"
#include "prtsub/subdiv/mesh_io.h"

namespace prtsub {

//! --order (unless without_order), --rays, --seed, --threads into `transfer`.
void add_transfer_options(ArgParser& args, TransferOptions& transfer, bool with_order = true);
//! --estimator and the progressive encoder's --pls-* options (bake).
void add_estimator_options(ArgParser& args, TransferOptions& t);

//! --threads T into `threads` (0: every core).
void add_threads_option(ArgParser& args, int& threads);

//! --batch B into `refine.batch` (adaptive refinement's faces per Embree batch).
void add_batch_option(ArgParser& args, RefineOptions& refine);

//! --report R.json into `path`.
void add_report_option(ArgParser& args, std::string& path);

//! What every command that bakes declares: the input mesh and how to load it, the transfer, the
//! signal, the fit and its samples, and the report.
struct BakeCli {
  std::string input, report;
  LoadOptions load;
  BakeOptions bake;
  //! The input, --crease-angle, the transfer options and --report.
  void add_common(ArgParser& args);
  //! --signal, --fit and every option of the fit and its samples.
  void add_fit(ArgParser& args);
  //! --refine and the options of adaptive and uniform refinement.
  void add_refinement(ArgParser& args);
  //! --basis and --sg-signed (bake alone: the other commands compare SH fits).
  void add_basis(ArgParser& args);
  //! The options after parsing: checks them (\throw UsageError naming the option) and fills in
  //! what derives from others (the source name).
  BakeOptions options() const;

 private:
  bool no_control_variate_ = false, no_noise_weighting_ = false, bounce_vertices_only_ = false, no_unshadowed_projection_ = false, lock_corners_ = false;
  int rays_fixed_ = 0;  // --rays-fixed R: no early stop
  bool rays_given_ = false;         // --rays: else --error chooses the first round
  bool sample_rays_given_ = false;  // --sample-rays: else the pilot chooses
  std::string bounces_;  // --bounces N|auto
  std::string albedo_, albedo_map_;  // --albedo A|R,G,B|vertex, --albedo-map PATH
  std::string alpha_ = "auto";       // --alpha A|auto
  std::string order_;    // --order N|auto
  std::string basis_;    // --basis sh|sg:N
  bool fit_given_ = false;  // --fit: else an SG bake's values are its vertices' own (point)
  std::vector<std::string> order_lights_;  // --order-light SPEC
};

//! Commands that need one order before they bake (compare, bench, eval --fits) refuse --order
//! auto. \throw UsageError naming `command`
void require_fixed_order(const BakeOptions& options, const char* command);

//! One progress line per pipeline stage, on a terminal.
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

}  // namespace prtsub
