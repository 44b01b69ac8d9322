// Simplification of a mesh to a triangle budget below its own count, by half-edge collapses
// ranked by how much they change a vertex signal (Vanhoey et al.'s functional metric) and the
// geometry (a memoryless quadric). Refinement's opposite: the signal is the same matrix of
// per-render-vertex values, so this room needs neither Embree nor SH.
#pragma once

#include <functional>
#include <string>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

enum class SimplifyMetric {
  Transfer,  //!< the signal's change plus the geometric quadric
  Geometry,  //!< the quadric alone (the baseline)
};
SimplifyMetric parse_simplify_metric(const std::string& name);  //!< transfer, geometry
const char* simplify_metric_name(SimplifyMetric m);

struct SimplifyOptions {
  size_t budget = 0;  //!< output triangle count (below the input's)
  SimplifyMetric metric = SimplifyMetric::Transfer;
  //! The signal's distance is measured in units of this value (eval's unit for transfer, the
  //! unshadowed norm); the quadric in units of the bounding-box diagonal.
  double value_scale = 1;
  //! weight of the quadric against the signal: a collapse that moves the surface by 0.1% of the
  //! diagonal costs as much as one that changes the signal by 3.2% of value_scale. 100 let the
  //! teapot's thin parts cross at 25% (RMS 7.4% against 2.6% at 1000; bunny the same at both)
  double geometry_weight = 1000;
  double min_angle_deg = 5;  //!< no collapse creates a face with a smaller angle than this (or than the faces it replaces)
  //! no collapse moves a boundary or a crease / UV-seam line by more than this share of the
  //! bounding-box diagonal
  double feature_tolerance = 1e-3;
  //! no collapse puts the kept vertex further than this share of the diagonal off the plane of
  //! a face the removed one had; while the budget is not reached it doubles, up to the maximum
  double surface_tolerance = 5e-3, max_surface_tolerance = 0.04;
  //! a vertex where three or more creases or seams meet may collapse along one of them, under the
  //! same line and surface tolerances; its sides that the kept vertex has no render vertex for
  //! keep their own render vertex, moved to the kept position (SimplifyStats::moved). False locks
  //! such corners, as ends of a line and features meeting a boundary always are
  bool collapse_corners = true;
};

struct SimplifyStats {
  size_t faces_before = 0, faces_after = 0, collapses = 0;
  double surface_tolerance = 0;  //!< the share of the diagonal the surface tolerance ended at
  size_t locked_vertices = 0;    //!< vertices never removed: ends of creases or seams, features meeting a boundary,
                                 //!< non-manifold faces' vertices (and crease corners, without collapse_corners)
  size_t corner_collapses = 0;   //!< collapses of a crease corner (collapse_corners)
  //! output render vertices a corner collapse moved to a neighbour's position: each keeps its normal,
  //! UVs and the value it had at its old one, which the caller should trace again there
  std::vector<uint32_t> moved;
  size_t kept_faces = 0;         //!< faces OpenMesh could not take (non-manifold, repeated corners): kept as they are
  double min_angle_after_deg = 0;
  size_t faces_below_min_angle = 0;  //!< after: none worse than the faces a collapse replaced
  //! collapses the guards refused, counted per evaluation (the decimater asks again as the
  //! neighbourhood changes): a face flipped, an angle, a boundary or feature line, a crease side
  size_t refused_flip = 0, refused_angle = 0, refused_line = 0, refused_crease_side = 0, refused_surface = 0;  //!< surface: moving it beyond the tolerance
  double seconds = 0;
  std::string warning;  //!< non-empty when the budget could not be met exactly, and why
};

//! Simplifies `mesh` and its #V by K `values` to `options.budget` triangles with OpenMesh's
//! Decimater and a module of ours. Collapses are half-edge collapses: every surviving vertex
//! keeps its position, normal, UVs and value (traced transfer stays valid). Guards, each a reason
//! to refuse a collapse: a face's normal flipping, a new face below
//! min_angle_deg (unless the faces it replaces were worse: an input's needle may be collapsed
//! into something better), the kept vertex lying off a removed face's plane by more than the surface tolerance
//! (doubled, up to its maximum, while the budget is not reached), a boundary or feature line moving by more than feature_tolerance, and
//! OpenMesh's own link condition (so a manifold input stays manifold). Creases and UV seams
//! (position edges whose faces do not share render vertices) are features: their vertices only
//! slide along them; where one ends (or meets a boundary) the vertex is locked, and where three or
//! more meet it collapses along one of them (options.collapse_corners), moving the render vertices
//! of its other sides to the kept position (stats.moved). Each
//! output face keeps the source_face of the input face it was (faces are never created).
//! \param values #V by K, may have no columns
//! \param removed_to if given, receives for every input render vertex its output index, or
//!        UINT32_MAX for removed ones
//! \param progress if given, told of collapses as they are made (in steps of 256), by every run
//!        (a relaxed run after the strict one counts again)
//! \param variance if given, #V: each value row's noise (its expected squared error, summed over
//!        its columns; 0 where exact, NaN where unknown, and either subtracts nothing). The signal
//!        term is then measured net of what that noise alone would give it, so that noise is not
//!        kept as if it were signal
SimplifyStats simplify(Mesh& mesh, RowMatrixXd& values, const SimplifyOptions& options,
                       std::vector<uint32_t>* removed_to = nullptr, const std::function<void(size_t collapses)>& progress = {},
                       const std::vector<double>* variance = nullptr);

}  // namespace prtsub
