// Transfer as the signal of adaptive refinement: edge error estimates over SH transfer
// vectors, and Embree transfer for the vertices refinement creates.
#pragma once

#include <string>

#include "prtsub/prt/transfer.h"
#include "prtsub/subdiv/refine.h"

namespace prtsub {

//! Edge error estimates (PIPELINE.md, "Refinement"; Δt = t_a − t_b).
enum class EdgeEstimate {
  Relative,   //!< (1) ‖Δt‖ / mean(‖t_a‖, ‖t_b‖)
  Shadow,     //!< (2) ‖Δt‖
  Curvature,  //!< (3) ‖Δt‖ / max(angle(n_a, n_b), θ0)
  Length,     //!< ours: ‖Δt‖ · |ab|, the edge's share of the surface integral of error
  Probe,      //!< ours: Length, plus each input face's transfer probed at its centroid
  //! ours: Probe with ‖Δt‖ · √|ab| (the probe weighted by the face's area to the 1/4): between
  //! Shadow's ‖Δt‖ and Length's ‖Δt‖ · |ab|, for steps that no input edge follows
  Root,
};

EdgeEstimate parse_estimate(const std::string& name);
const char* estimate_name(EdgeEstimate e);

struct TransferSignalOptions {
  EdgeEstimate estimate = EdgeEstimate::Root;
  double curvature_guard_deg = 10;  //!< θ0 of the curvature estimate
  TransferOptions transfer;        //!< order, rays, seed, threads of new vertices' transfer
  //! If set: the mesh whose surface the scene is, for refining a mesh that only lies near it (a
  //! simplified one). New vertices and probes are then traced at their closest points on it,
  //! with its interpolated normal where that is within 60° of their own (their own across a
  //! crease; not moved where it faces away: a thin wall's other side); the refined mesh's
  //! geometry is not moved. Not owned.
  const Mesh* project_onto = nullptr;
  //! If set: the signal is these spherical-Gaussian lobes' coefficients (sg_transfer with
  //! `transfer`), right-multiplied by lobe_metric, the Cholesky factor L of their Gram matrix
  //! (G = L Lᵀ), so that refinement's Euclidean distances are L² distances on the sphere, as they
  //! are for SH. Not owned.
  const SgBasis* lobes = nullptr;
  Eigen::MatrixXd lobe_metric;
};

//! An estimate's value on one edge (Probe ranks edges as Length does, Root as ‖Δt‖·√|ab|).
//! \param curvature_guard_deg θ0 of the curvature estimate
double edge_estimate(EdgeEstimate estimate, const EdgeView& edge, double curvature_guard_deg = 10);

//! The extra key of a probed face in the unit of the edges' estimate: the probe's distance from
//! the corners' mean times √(3·area) (Probe) or its square root (Root); 0 for other estimates.
//! \param probed the transfer traced at the face's centroid (f.K values)
double probe_estimate(EdgeEstimate estimate, const FaceProbe& face, const double* probed);

//! Moves points (and their normals and offsets) to their closest points on `surface` among the
//! faces facing their way (closest_points), as a projecting TransferSignal traces its vertices:
//! with the surface's interpolated normal and offset
//! where that normal is within 60° of the point's own, keeping its own normal (across a crease)
//! otherwise, and not moving it where the surface faces the other way (a thin wall's far side).
//! \param surface_offsets the surface's vertex offset directions (vertex_offset_directions)
void project_onto_surface(const Mesh& surface, const RowMatrixX3d& surface_offsets, RowMatrixX3d& points, RowMatrixX3d& normals,
                          RowMatrixX3d* offsets, int threads);

//! Refinement's signal: transfer computed with the scene of the (unchanged) geometry.
class TransferSignal : public RefinementSignal {
 public:
  TransferSignal(const RayScene& scene, const TransferSignalOptions& options);
  double edge_error(const EdgeView& edge) const override;
  void compute_values(const std::vector<NewVertex>& batch, const RowMatrixXd& parent_values, RowMatrixXd& values) override;
  void probe_faces(const std::vector<FaceProbe>& faces, std::vector<double>& extra) override;
  uint64_t rays() const { return rays_; }
  //! The estimated variance of every vertex this signal computed, by render-vertex index (0 for
  //! vertices it did not compute): see shadowed_transfer.
  const std::vector<double>& variance() const { return variance_; }

 private:
  //! The signal at points: SH transfer, or the metric's lobes (variance then 0).
  RowMatrixXd trace(const RowMatrixX3d& points, const RowMatrixX3d& normals, const TransferOptions& o, const RowMatrixX3d* offsets,
                    std::vector<double>* variance);
  //! Moves points (and their normals and offsets) to their closest points on project_onto.
  void project(RowMatrixX3d& points, RowMatrixX3d& normals, RowMatrixX3d* offsets);
  const RayScene& scene_;
  TransferSignalOptions options_;
  RowMatrixX3d source_offsets_;  //!< project_onto's vertex offset directions
  uint64_t rays_ = 0;
  std::vector<double> variance_;
};

}  // namespace prtsub
