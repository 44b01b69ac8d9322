#include "cli/bake_options.h"

#include "prt/sampling.h"

namespace prtsub {

void FitCli::add(ArgParser& args) {
  args.option("--signal", "transfer|ao", "what to bake: SH transfer, or ambient occlusion (one ao value) [default transfer]", &signal);
  args.option("--fit", "point|average|lsq", "vertex values: traced at the vertex, averaged from surface samples, or the\n"
              "least-squares fit to them (Kavan et al. 2011) [default lsq]", &fit);
  args.option("--alpha", "A", "lsq: regulariser weight; 0 is the plain least-squares optimum [default 0.1]", &settings.fit.alpha, 0.0, 1e12);
  args.option("--regularizer", "edge|gradient", "lsq: penalise gradient jumps across edges, or gradients [default edge]", &regularizer);
  args.option("--mass", "analytic|sampled", "lsq: exact mass matrix, or the samples' own [default analytic]", &mass);
  args.option("--solver", "auto|cholmod", "lsq: conjugate gradients (analytic mass; CHOLMOD if they stall), or always a\n"
              "CHOLMOD Cholesky factorisation [default auto]", &solver);
  args.flag("--no-control-variate", "lsq, analytic mass: estimate b as the paper does, without the point samples' control\n"
            "variate (for comparison; noisier)", &no_control_variate);
  args.option("--samples-per-triangle", "N", "fit: average surface samples per triangle [default 16]", &settings.samples.per_triangle, 0.0, 1e6);
  args.option("--sample-density", "D", "fit: samples per unit area instead (world units)", &settings.samples.density, 0.0, 1e30);
  args.option("--min-samples", "M", "fit: samples every triangle gets at least [default 1]", &min_samples, 0, 1 << 20);
  args.option("--sample-rays", "R", "fit: rays per surface sample [default 16]", &settings.sample_rays, 1, 1 << 20);
}

void FitCli::apply(BakeSettings& b) const {
  b.signal = signal == "ao" ? AssetSignal::Ao : AssetSignal::Transfer;
  if (signal != "ao" && signal != "transfer") throw UsageError("--signal must be transfer or ao, got '" + signal + "'");
  if (b.signal == AssetSignal::Ao) b.transfer.order = 1;  // AO is order-1 transfer, rescaled
  b.fit = settings.fit;
  try {
    b.fit.method = parse_fit_method(fit);
    b.fit.regularizer = parse_regularizer(regularizer);
    b.fit.mass = parse_mass_matrix(mass);
    b.fit.solver = parse_fit_solver(solver);
  } catch (const InputError& e) {
    throw UsageError(e.what());
  }
  b.fit.threads = b.transfer.threads;
  b.fit.control_variate = !no_control_variate;
  b.samples = settings.samples;
  b.samples.min_per_triangle = static_cast<size_t>(min_samples);
  b.samples.seed = mix64(b.transfer.seed + 17);
  b.sample_rays = settings.sample_rays;
}

StageProgress::StageProgress() : enabled_(stderr_is_terminal()) {}
StageProgress::~StageProgress() { finish(); }
void StageProgress::finish() {
  if (current_) current_->finish();
  current_.reset();
}
BakeProgress StageProgress::callbacks() {
  BakeProgress p;
  p.stage = [this](const char* stage, size_t total) {
    finish();
    current_ = std::make_unique<Progress>(stage, total, enabled_);
  };
  p.add = [this](size_t n) {
    if (current_) current_->add(n);
  };
  return p;
}

void add_fit_report(Report& r, const BakeResult& res, const BakeSettings& b) {
  r.set("signal", b.signal == AssetSignal::Ao ? "ao" : "transfer");
  r.set("fit", fit_method_name(b.fit.method));
  if (b.fit.method == FitMethod::Point) return;
  r.set("samples", static_cast<uint64_t>(res.fit_data.samples.size()));
  r.set("sample_rays", b.sample_rays);
  r.set("seconds_samples", res.seconds_samples);
  r.set("seconds_fit", res.seconds_fit);
  if (b.fit.method != FitMethod::LeastSquares) return;
  r.set("alpha", b.fit.alpha);
  r.set("regularizer", regularizer_name(b.fit.regularizer));
  r.set("mass", mass_matrix_name(b.fit.mass));
  r.set("fit_solver", res.fit.solver);
  r.set("fit_cg_iterations", res.fit.cg_iterations);
  r.set("fit_unsupported_vertices", static_cast<uint64_t>(res.fit.unsupported));
  r.set("fit_stabilizer", res.fit.stabilizer);
  r.set("fit_system_nonzeros", static_cast<uint64_t>(res.fit.system_nonzeros));
  r.set("fit_factor_nonzeros", static_cast<uint64_t>(res.fit.factor_nonzeros));
  r.set("solve_memory_mib", res.fit.solve_memory_mib);
  r.set("seconds_fit_assemble", res.fit.seconds_assemble);
  r.set("seconds_fit_factor", res.fit.seconds_factor);
  r.set("seconds_fit_solve", res.fit.seconds_solve);
}

}  // namespace prtsub
