#include "cli/pipeline.h"

#include <chrono>

#include "prt/ray_scene.h"
#include "subdiv/exceptions.h"

namespace prtsub {
namespace {
double since(std::chrono::steady_clock::time_point& t) {
  auto now = std::chrono::steady_clock::now();
  double s = std::chrono::duration<double>(now - t).count();
  t = now;
  return s;
}
}  // namespace

BakeResult run_bake(const BakeSettings& s, const ProgressFn& progress) {
  if (s.refine != "none" && s.refine != "adaptive" && s.refine != "uniform")
    throw InputError("--refine must be none, adaptive or uniform, got '" + s.refine + "'");
  check_transfer_options(s.transfer);
  const auto start = std::chrono::steady_clock::now();
  auto t = start;
  BakeResult r;
  r.mesh = load_mesh(s.input, s.load);
  r.seconds_load = since(t);
  if (s.refine == "uniform") {
    r.mesh = refine_uniform(r.mesh, s.uniform);
    r.seconds_refine = since(t);
  }
  // Adaptive and linear uniform refinement keep the geometry: one scene serves throughout.
  RayScene scene(r.mesh.positions, position_triangles(r.mesh));
  r.seconds_scene = since(t);
  TransferStats stats;
  const RowMatrixX3d offsets = vertex_offset_directions(r.mesh);
  r.transfer = shadowed_transfer(scene, vertex_positions(r.mesh), r.mesh.normals, s.transfer, &stats, progress, &offsets);
  r.rays = stats.rays;
  r.seconds_transfer = since(t);
  if (s.refine == "adaptive") {
    TransferSignalOptions so;
    so.estimate = s.estimate;
    so.transfer = s.transfer;
    TransferSignal signal(scene, so);
    r.refine = refine_adaptive(r.mesh, r.transfer, signal, RefineOptions{s.budget, s.batch, s.max_edge});
    r.rays += signal.rays();
    r.seconds_refine = since(t);
    if (!r.refine.warning.empty()) r.warnings.push_back(r.refine.warning);
  }
  r.seconds_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  r.metadata = sh_convention_metadata(s.transfer.order);
  r.metadata.push_back({"source", s.input});
  r.metadata.push_back({"rays", std::to_string(s.transfer.rays)});
  r.metadata.push_back({"seed", std::to_string(s.transfer.seed)});
  r.metadata.push_back({"threads", std::to_string(s.transfer.threads) + " (results do not depend on it)"});
  r.metadata.push_back({"crease_angle", std::to_string(s.load.crease_angle_deg)});
  r.metadata.push_back({"normals", r.mesh.normals_from_file ? "file" : "computed"});
  r.metadata.push_back({"estimator", "cosine-lattice cross-fitted-control-variate"});
  r.metadata.push_back({"refine", s.refine});
  if (s.refine == "adaptive") {
    r.metadata.push_back({"budget", std::to_string(s.budget)});
    r.metadata.push_back({"estimate", estimate_name(s.estimate)});
    r.metadata.push_back({"max_edge", std::to_string(s.max_edge)});
    r.metadata.push_back({"batch", std::to_string(s.batch)});
  }
  if (s.refine == "uniform") {
    r.metadata.push_back({"levels", std::to_string(s.uniform.levels)});
    r.metadata.push_back({"scheme", s.uniform.scheme == UniformScheme::Loop ? "loop" : "linear"});
  }
  r.metadata.push_back({"generator", std::string("prtsub ") + kPrtsubVersion});
  return r;
}

}  // namespace prtsub
