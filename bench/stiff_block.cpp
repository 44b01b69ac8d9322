// The fit's solve on one mesh at several stiff-row thresholds (FitOptions::stiff_mass): how many
// rows CG's directly solved block holds, what its factor costs, how many iterations CG then needs
// and how long assembly, factorisation and solve take, against CHOLMOD on the whole system.
// Threshold 0 is Jacobi alone. The system is `prtsub bench --solve`'s: every vertex an unknown,
// the default samples, pseudo-random face moments and prior, order 4 (16 right-hand sides).
// Best of REPEAT runs per row; each threshold's row is run in turn, then CHOLMOD's.
// usage: bash bench/stiff_block.sh BUILD SCENE "THRESHOLDS" [REPEAT]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "prtsub/prt/bake.h"
#include "prtsub/prt/fit.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/mesh_io.h"
#include "prtsub/subdiv/random.h"

using namespace prtsub;

int main(int argc, char** argv) {
  if (argc < 3) return std::fprintf(stderr, "usage: stiff_block SCENE \"THRESHOLDS\" [REPEAT]\n"), 2;
  const Mesh mesh = load_mesh(argv[1]);
  std::vector<double> thresholds;
  std::istringstream in(argv[2]);
  for (double t; in >> t;) thresholds.push_back(t);
  const int repeat = argc > 3 ? std::atoi(argv[3]) : 2;
  const BakeOptions b;
  const SurfaceSamples samples = make_surface_samples(mesh, b.samples);
  const Eigen::Index K = sh_count(b.transfer.order);
  FaceMoments moments{RowMatrixXd(Eigen::Index(3 * mesh.num_faces()), K), {}};
  RowMatrixXd prior(Eigen::Index(mesh.num_vertices()), K);
  Rng rng(b.transfer.seed, 0);
  for (Eigen::Index i = 0; i < moments.rows.size(); ++i) moments.rows.data()[i] = rng.uniform();
  for (Eigen::Index i = 0; i < prior.size(); ++i) prior.data()[i] = rng.uniform();
  std::printf("| threshold | stiff rows | block factor / system | solver | CG iterations | assemble s | factor s | solve s | total s | max diff from CHOLMOD |\n");
  std::printf("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|\n");
  FitOptions cholmod = b.fit;
  cholmod.method = FitMethod::LeastSquares, cholmod.solver = FitSolver::Cholmod;
  const RowMatrixXd exact = fit_vertex_values(mesh, samples, moments, prior, cholmod);
  const double scale = exact.cwiseAbs().maxCoeff();
  auto row = [&](const std::string& label, const FitOptions& o) {
    FitStats best;
    double best_total = INFINITY, diff = 0;
    for (int r = 0; r < repeat; ++r) {
      FitStats st;
      const RowMatrixXd x = fit_vertex_values(mesh, samples, moments, prior, o, &st);
      const double total = st.seconds_assemble + st.seconds_factor + st.seconds_solve;
      if (total < best_total) best_total = total, best = st, diff = (x - exact).cwiseAbs().maxCoeff() / scale;
    }
    const double n = double(best.unknowns - best.unsupported);
    std::printf("| %s | %zu (%.1f%%) | %.3f | %s | %d | %.3f | %.3f | %.3f | %.3f | %.1e |\n", label.c_str(), best.stiff_rows,
                100.0 * double(best.stiff_rows) / n, double(best.stiff_factor_entries) / double(best.system_nonzeros), best.solver.c_str(),
                best.cg_iterations, best.seconds_assemble, best.seconds_factor, best.seconds_solve, best_total, diff);
  };
  for (double t : thresholds) {
    FitOptions o = b.fit;
    o.method = FitMethod::LeastSquares, o.stiff_mass = t;
    char label[32];
    std::snprintf(label, sizeof label, "%g", t);
    row(label, o);
  }
  row("CHOLMOD", cholmod);
}
