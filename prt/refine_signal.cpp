// Edge estimates see only the two vertices of an edge. That is cheap, but a shadow crossing a
// long edge between two lit vertices is invisible to them; max_edge pre-refinement (D3DX's
// answer) bounds how long such an edge can be.
//
// "Length" is ours. The surface RMS error that eval measures integrates squared error over
// area. An edge whose endpoint transfers differ by Δ leaves an interpolation error of order
// Δ over a strip whose area grows with the edge's length, so ranking by ‖Δt‖·|ab| (rather
// than ‖Δt‖ alone) spends splits where they buy the most error per triangle, instead of on
// tiny edges at a sharp shadow. BENCHMARKS.md has the measurement that chose the default.
//
// "Probe" is ours too. A large input face whose corners are all lit can hide a shadow inside
// (the floor under a table, a slab under a house): no edge estimate sees it. Before the
// adaptive pass, each input face's transfer is traced at its centroid; its distance from the
// corners' mean, times sqrt(3·area) (the edge-length scale of a triangle of that area,
// summed over three edges), joins the face's key until the face is first split. After that
// the new vertices themselves see the shadow. Cost: one transfer per input face.
#include "prtsub/prt/refine_signal.h"

#include "prtsub/prt/sg_basis.h"

#include "prtsub/prt/closest_point.h"

#include <algorithm>
#include <cmath>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

EdgeEstimate parse_estimate(const std::string& name) {
  if (name == "relative") return EdgeEstimate::Relative;
  if (name == "shadow") return EdgeEstimate::Shadow;
  if (name == "curvature") return EdgeEstimate::Curvature;
  if (name == "length") return EdgeEstimate::Length;
  if (name == "probe") return EdgeEstimate::Probe;
  if (name == "root") return EdgeEstimate::Root;
  throw InputError("unknown estimate '" + name + "' (relative, shadow, curvature, length, probe, root)");
}

const char* estimate_name(EdgeEstimate e) {
  switch (e) {
    case EdgeEstimate::Relative: return "relative";
    case EdgeEstimate::Shadow: return "shadow";
    case EdgeEstimate::Curvature: return "curvature";
    case EdgeEstimate::Length: return "length";
    case EdgeEstimate::Probe: return "probe";
    case EdgeEstimate::Root: return "root";
  }
  return "?";
}

double edge_estimate(EdgeEstimate estimate, const EdgeView& e, double curvature_guard_deg) {
  double d2 = 0, a2 = 0, b2 = 0;
  for (int i = 0; i < e.K; ++i) {
    const double d = e.va[i] - e.vb[i];
    d2 += d * d, a2 += e.va[i] * e.va[i], b2 += e.vb[i] * e.vb[i];
  }
  const double diff = std::sqrt(d2);
  switch (estimate) {
    case EdgeEstimate::Relative: {
      const double mean = 0.5 * (std::sqrt(a2) + std::sqrt(b2));
      return mean > 1e-12 ? diff / mean : (diff > 0 ? diff / 1e-12 : 0.0);
    }
    case EdgeEstimate::Shadow: return diff;
    case EdgeEstimate::Curvature: {
      const double angle = std::acos(std::clamp(e.na.dot(e.nb), -1.0, 1.0));
      return diff / std::max(angle, curvature_guard_deg * M_PI / 180);
    }
    case EdgeEstimate::Length:
    case EdgeEstimate::Probe: return diff * (e.pa - e.pb).norm();
    case EdgeEstimate::Root: return diff * std::sqrt((e.pa - e.pb).norm());
  }
  return diff;
}

double probe_estimate(EdgeEstimate estimate, const FaceProbe& f, const double* probed) {
  if (estimate != EdgeEstimate::Probe && estimate != EdgeEstimate::Root) return 0;
  double d2 = 0;
  for (int k = 0; k < f.K; ++k) {
    const double d = probed[k] - (f.va[k] + f.vb[k] + f.vc[k]) / 3;
    d2 += d * d;
  }
  // In the unit of the edges' estimate: a length (√(3a), an equilateral edge), or its root.
  const double length = std::sqrt(3 * f.area);
  return std::sqrt(d2) * (estimate == EdgeEstimate::Root ? std::sqrt(length) : length);
}

TransferSignal::TransferSignal(const RayScene& scene, const TransferSignalOptions& options)
    : scene_(scene), options_(options) {
  TransferOptions checked = options.transfer;
  if (options.lobes) checked.progressive.non_negative = false;  // sg_transfer's to keep, refused for SH
  check_transfer_options(checked);
  if (options.project_onto) source_offsets_ = vertex_offset_directions(*options.project_onto);
}

void project_onto_surface(const Mesh& m, const RowMatrixX3d& surface_offsets, RowMatrixX3d& points, RowMatrixX3d& normals,
                          RowMatrixX3d* offsets, int threads) {
  const std::vector<SurfaceLocation> at = closest_points(m, points, threads, &normals);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const SurfaceLocation& l = at[size_t(i)];
    const Triangle& t = m.triangles[l.face];
    Eigen::Vector3d p = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero(), d = Eigen::Vector3d::Zero();
    for (int c = 0; c < 3; ++c) {
      p += l.barycentric[c] * m.point(t[c]);
      n += l.barycentric[c] * m.normals.row(t[c]).transpose();
      d += l.barycentric[c] * surface_offsets.row(t[c]).transpose();
    }
    // The source's normal where it faces the vertex's way; on the other side of a thin wall, not
    // moved at all; across a crease (the closest face is the other side's), moved with its own.
    const double agree = n.norm() > 1e-12 ? n.normalized().dot(normals.row(i)) : 0;
    if (agree < -0.1) continue;
    points.row(i) = p.transpose();
    if (agree < 0.5) continue;
    normals.row(i) = n.normalized().transpose();
    if (offsets) offsets->row(i) = (d.norm() > 1e-12 ? Eigen::Vector3d(d.normalized()) : n.normalized()).transpose();
  }
}

void TransferSignal::project(RowMatrixX3d& points, RowMatrixX3d& normals, RowMatrixX3d* offsets) {
  project_onto_surface(*options_.project_onto, source_offsets_, points, normals, offsets, options_.transfer.threads);
}

double TransferSignal::edge_error(const EdgeView& e) const {
  return edge_estimate(options_.estimate, e, options_.curvature_guard_deg);
}

void TransferSignal::compute_values(const std::vector<NewVertex>& batch, const RowMatrixXd&, RowMatrixXd& values) {
  if (batch.empty()) return;
  RowMatrixX3d points(static_cast<Eigen::Index>(batch.size()), 3), normals(static_cast<Eigen::Index>(batch.size()), 3);
  std::vector<uint32_t> position_of(batch.size());
  for (size_t i = 0; i < batch.size(); ++i) {
    points.row(static_cast<Eigen::Index>(i)) = batch[i].position.transpose();
    normals.row(static_cast<Eigen::Index>(i)) = batch[i].normal.transpose();
    position_of[i] = batch[i].position_index;
  }
  // Both sides of a split crease are made by one split, so they are in this batch together.
  RowMatrixX3d offsets = offset_directions(position_of, normals);
  if (options_.project_onto) project(points, normals, &offsets);
  // A batch's vertices have consecutive indices: stream = render-vertex index.
  TransferOptions o = options_.transfer;
  o.stream_offset = batch.front().index;
  std::vector<double> variance;
  values = trace(points, normals, o, &offsets, &variance);
  for (size_t i = 0; i < batch.size(); ++i) {
    if (batch[i].index >= variance_.size()) variance_.resize(batch[i].index + 1, 0.0);
    variance_[batch[i].index] = variance[i];
  }
}

}  // namespace prtsub

namespace prtsub {

void TransferSignal::probe_faces(const std::vector<FaceProbe>& faces, std::vector<double>& extra) {
  extra.clear();
  const bool root = options_.estimate == EdgeEstimate::Root;
  if ((options_.estimate != EdgeEstimate::Probe && !root) || faces.empty()) return;
  RowMatrixX3d points(static_cast<Eigen::Index>(faces.size()), 3), normals(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) {
    points.row(static_cast<Eigen::Index>(i)) = faces[i].centroid.transpose();
    normals.row(static_cast<Eigen::Index>(i)) = faces[i].normal.transpose();
  }
  if (options_.project_onto) project(points, normals, nullptr);
  TransferOptions o = options_.transfer;
  o.stream_offset = uint64_t(1) << 40;  // streams apart from every vertex's
  RowMatrixXd t = trace(points, normals, o, nullptr, nullptr);
  extra.resize(faces.size());
  for (size_t i = 0; i < faces.size(); ++i) extra[i] = probe_estimate(options_.estimate, faces[i], t.row(static_cast<Eigen::Index>(i)).data());
}

}  // namespace prtsub

namespace prtsub {

RowMatrixXd TransferSignal::trace(const RowMatrixX3d& points, const RowMatrixX3d& normals, const TransferOptions& o, const RowMatrixX3d* offsets,
                                  std::vector<double>* variance) {
  if (options_.lobes) {
    rays_ += static_cast<uint64_t>(points.rows()) * static_cast<uint64_t>(o.rays);
    if (variance) variance->assign(static_cast<size_t>(points.rows()), 0.0);
    return sg_transfer(scene_, points, normals, *options_.lobes, o, offsets) * options_.lobe_metric;
  }
  TransferStats stats;
  RowMatrixXd t = shadowed_transfer(scene_, points, normals, o, &stats, {}, offsets, variance);
  rays_ += stats.rays;
  return t;
}

}  // namespace prtsub
