// Adaptive refinement of a mesh to an exact triangle budget, driven by per-edge error
// estimates of a vertex signal. The signal (transfer, in prtsub) is behind an interface, so
// this room needs neither Embree nor SH and is tested with synthetic signals.
#pragma once

#include <string>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

//! One side of an edge, as a face sees it: its two render vertices with their data.
struct EdgeView {
  Eigen::Vector3d pa, pb, na, nb;  //!< positions and unit normals
  const double* va;                //!< signal of vertex a (K values)
  const double* vb;
  int K;
};

//! A vertex the refinement created: the midpoint of render vertices a and b.
struct NewVertex {
  uint32_t index;                  //!< its render-vertex index
  uint32_t a, b;                   //!< parents
  uint32_t position_index;         //!< its position (shared by both sides of a crease)
  Eigen::Vector3d position, normal;
};

//! A face of the input, as the signal's optional interior probe sees it.
struct FaceProbe {
  Eigen::Vector3d centroid, normal;  //!< normal: the corners' normals averaged
  double area;
  const double* va;  //!< the corners' signal (K values each)
  const double* vb;
  const double* vc;
  int K;
};

//! What refinement asks of the signal.
class RefinementSignal {
 public:
  virtual ~RefinementSignal() = default;
  //! Optional: an extra key for each face present when the adaptive pass starts, kept until the
  //! face is first split. Estimates see only vertices; a probe inside a large face can see a
  //! shadow that none of its corners does. Leave `extra` empty for none.
  virtual void probe_faces(const std::vector<FaceProbe>& faces, std::vector<double>& extra) {
    (void)faces;
    extra.clear();
  }
  //! Error estimate of an edge; larger is worse; must be finite and >= 0.
  virtual double edge_error(const EdgeView& edge) const = 0;
  //! Fills one row of `values` (#batch by K, row-major) per new vertex. Called once per batch
  //! with every vertex the batch created; `parent_values` holds their linear interpolation.
  virtual void compute_values(const std::vector<NewVertex>& batch, const RowMatrixXd& parent_values,
                              RowMatrixXd& values) = 0;
};

struct RefineOptions {
  size_t budget = 0;       //!< output triangle count
  //! faces popped before the signal is asked for new values; at most 1/16 of the faces there
  //! are and 1/64 of the triangles the refinement adds, so that small meshes and short
  //! refinements are not refined on stale keys
  size_t batch = 256;
  double max_edge = 0;     //!< > 0: first split every edge longer than this (within the budget)
};

struct RefineStats {
  size_t splits = 0, boundary_splits = 0, new_vertices = 0, batches = 0;
  size_t pre_refinement_splits = 0;
  size_t faces_popped = 0;  //!< faces taken from the queue
  size_t probed_faces = 0;  //!< faces the signal probed inside
  size_t walk_steps = 0;    //!< faces visited along longest-edge paths (linear in splits + pops)
  size_t non_manifold_edges = 0;       //!< input edges shared by more than two faces
  size_t non_manifold_splits = 0;      //!< splits of such edges (all k faces at once)
  size_t non_manifold_edges_kept = 0;  //!< never split: edges a face has twice (a repeated position)
  double min_angle_before_deg = 0, min_angle_after_deg = 0;
  size_t faces_below_1deg_before = 0, faces_below_1deg_after = 0;  //!< counting faces without area
  double seconds_signal = 0, seconds_total = 0;
  std::string warning;  //!< non-empty when the budget could not be met exactly, and why
};

//! Refines `mesh` (and the #V by K `values` of its render vertices) towards `options.budget`
//! triangles. Faces are popped by the sum of their edges' errors; each is split by longest-
//! edge bisection (Rivara's LEPP), which splits an edge in every face that has it, so the mesh
//! stays conforming across creases, boundaries and welded parts, and angles never fall below
//! half the smallest input angle. New vertices lie at edge midpoints; normals (per crease
//! side) are interpolated and renormalised, the mesh's UVs and `attributes` (#V by A) interpolated
//! linearly, and every face keeps its source_face. An edge shared by k > 2 faces is split in
//! all k at once. A budget at or below the input's count leaves the mesh as it is (with a warning). Closed
//! surfaces only hold even triangle counts (3F = 2E); an odd budget on one yields budget − 1.
//! \param attributes may be null
RefineStats refine_adaptive(Mesh& mesh, RowMatrixXd& values, RefinementSignal& signal, const RefineOptions& options,
                            RowMatrixXd* attributes = nullptr);

//! Smallest corner angle over faces of non-zero area, in degrees.
double min_angle_deg(const Mesh& mesh);

//! Smallest corner angle of each face in degrees (0 for a face without area).
std::vector<double> face_min_angles_deg(const Mesh& mesh);

}  // namespace prtsub
