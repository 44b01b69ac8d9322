#include "cli/pipeline.h"

#include <algorithm>
#include <chrono>

#include "prt/ray_scene.h"
#include "prt/sampling.h"
#include "prt/sh.h"
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

size_t clamp_ao(RowMatrixXd& t0) {
  const double hi = 1 / kAoPerT0;
  size_t moved = 0;
  for (Eigen::Index i = 0; i < t0.size(); ++i) {
    double& v = t0.data()[i];
    if (v < 0 || v > hi) v = std::clamp(v, 0.0, hi), ++moved;
  }
  return moved;
}

FaceMoments trace_face_moments(const Mesh& mesh, const RayScene& scene, const SurfaceSamples& samples,
                               const TransferOptions& options, TransferStats* stats, const ProgressFn& progress) {
  // Samples are traced in chunks of at most kChunk, each reduced to its three moment rows as
  // soon as it is traced: storing every sample's transfer would cost a row per sample and the
  // time to write it. A face's chunks are then summed in order, so the result does not depend
  // on the threads; chunks rather than faces, because one face may hold most of the samples
  // (a floor) and one thread traces a chunk.
  constexpr size_t kChunk = 64;
  const size_t F = mesh.num_faces();
  std::vector<size_t> chunk_begin{0}, first_chunk(F + 1, 0);
  for (size_t f = 0; f < F; ++f) {
    first_chunk[f] = chunk_begin.size() - 1;
    for (size_t k = samples.begin[f]; k < samples.begin[f + 1]; k += kChunk) chunk_begin.push_back(std::min(k + kChunk, samples.begin[f + 1]));
  }
  first_chunk[F] = chunk_begin.size() - 1;
  const Eigen::Index K = sh_count(options.order);
  RowMatrixXd partial(static_cast<Eigen::Index>(3 * (chunk_begin.size() - 1)), K);
  shadowed_transfer_groups(
      scene, samples.points, samples.normals, chunk_begin, options,
      [&](size_t c, const double* values, size_t) {
        sample_moments(samples, chunk_begin[c], chunk_begin[c + 1], values, K, partial.row(static_cast<Eigen::Index>(3 * c)).data());
      },
      stats, progress, &samples.offsets);
  FaceMoments m{RowMatrixXd::Zero(static_cast<Eigen::Index>(3 * F), K)};
  for (size_t f = 0; f < F; ++f)
    for (size_t c = first_chunk[f]; c < first_chunk[f + 1]; ++c)
      m.rows.middleRows(static_cast<Eigen::Index>(3 * f), 3) += partial.middleRows(static_cast<Eigen::Index>(3 * c), 3);
  return m;
}

FitData sample_signal(const Mesh& mesh, const RayScene& scene, const BakeSettings& s, const BakeProgress& progress) {
  auto t = std::chrono::steady_clock::now();
  FitData d;
  d.samples = make_surface_samples(mesh, s.samples);
  TransferOptions to = s.transfer;
  to.rays = s.sample_rays;
  to.seed = mix64(s.transfer.seed ^ 0x5A3D1E5ull);  // independent of the vertices' rays
  to.stream_offset = 0;
  if (progress.stage) progress.stage("samples", d.samples.size());
  TransferStats stats;
  d.moments = trace_face_moments(mesh, scene, d.samples, to, &stats, progress.add);
  d.rays = stats.rays;
  d.seconds = since(t);
  return d;
}

BakeResult run_bake(const BakeSettings& s_in, const BakeProgress& progress) {
  BakeSettings s = s_in;
  if (s.signal == AssetSignal::Ao) s.transfer.order = 1;  // AO is order-1 transfer, rescaled
  if (s.sample_rays < 1 || s.sample_rays > (1 << 20))
    throw InputError("--sample-rays must be between 1 and 1048576, got " + std::to_string(s.sample_rays));
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
  if (progress.stage) progress.stage("transfer", r.mesh.num_vertices());
  r.transfer = shadowed_transfer(scene, vertex_positions(r.mesh), r.mesh.normals, s.transfer, &stats, progress.add, &offsets);
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
  if (s.fit.method != FitMethod::Point) {
    r.fit_data = sample_signal(r.mesh, scene, s, progress);
    r.rays += r.fit_data.rays;
    r.seconds_samples = since(t);
    r.point = r.transfer;
    r.transfer = fit_vertex_values(r.mesh, r.fit_data.samples, r.fit_data.moments, r.point, s.fit, &r.fit);
    r.seconds_fit = since(t);
    if (!r.fit.warning.empty()) r.warnings.push_back(r.fit.warning);
  }
  if (r.point.size() == 0) r.point = r.transfer;
  if (s.signal == AssetSignal::Ao) {
    // The paper's choice: clamp after the fit (a constrained solve is rarely worth it).
    r.clamped = clamp_ao(r.transfer);
    clamp_ao(r.point);
  }
  r.seconds_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  r.metadata = s.signal == AssetSignal::Ao ? ao_metadata() : sh_convention_metadata(s.transfer.order);
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
  r.metadata.push_back({"fit", fit_method_name(s.fit.method)});
  if (s.fit.method != FitMethod::Point) {
    r.metadata.push_back({"samples", std::to_string(r.fit_data.samples.size())});
    r.metadata.push_back({"sample_rays", std::to_string(s.sample_rays)});
  }
  if (s.fit.method == FitMethod::LeastSquares) {
    r.metadata.push_back({"alpha", std::to_string(s.fit.alpha)});
    r.metadata.push_back({"regularizer", regularizer_name(s.fit.regularizer)});
    r.metadata.push_back({"mass", mass_matrix_name(s.fit.mass)});
  }
  r.metadata.push_back({"generator", std::string("prtsub ") + kPrtsubVersion});
  return r;
}

}  // namespace prtsub
