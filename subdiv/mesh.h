// The triangle mesh every stage of prtsub passes along.
//
// Topology and values live apart: `positions` are welded (one row per distinct point in
// space), while render vertices carry what a GPU vertex carries (a normal, UVs, and values
// such as transfer). A position on a crease or a UV seam has one render vertex per side. Triangles
// index render vertices; `vertex_position` maps each back to its position, so topology
// (edges, adjacency, conforming splits) is always taken over positions.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace prtsub {

using RowMatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixX2d = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
using Triangle = std::array<uint32_t, 3>;

//! Computed normals: edges whose faces meet at a sharper angle are creases.
constexpr double kDefaultCreaseAngleDeg = 60.0;

//! Defects found while loading; tolerated, counted, and reported in every summary.
struct MeshDefects {
  size_t degenerate_faces = 0;       //!< faces with a repeated index after welding (dropped)
  size_t zero_area_faces = 0;        //!< distinct corners but area <= (1e-7 * bbox diagonal)^2 (kept)
  size_t duplicate_faces = 0;        //!< same three positions as an earlier face, either winding (kept)
  size_t unreferenced_vertices = 0;  //!< input vertices used by no face (dropped)
  size_t welded_vertices = 0;        //!< input vertices merged into an earlier one of equal position
  size_t winding_conflicts = 0;      //!< two-face edges traversed in the same direction by both
  size_t non_manifold_edges = 0;     //!< edges with more than two faces
  size_t boundary_edges = 0;         //!< edges with one face (information, not a defect)
  size_t polygons_triangulated = 0;  //!< input faces with more than three corners
  size_t invalid_file_normals = 0;   //!< zero or non-finite normals in the file (recomputed)
  size_t corners_without_uv = 0;     //!< corners of a mesh with UVs that the file gave none (0, 0)
  size_t vertices_without_colour = 0;  //!< OBJ vertices of a coloured mesh that the file gave no colour (white)
};

//! A triangle mesh with welded positions and per-crease-side render vertices.
struct Mesh {
  RowMatrixX3d positions;                //!< #P by 3, welded
  std::vector<uint32_t> vertex_position;  //!< #V, render vertex -> row of positions
  RowMatrixX3d normals;                  //!< #V by 3, unit length
  //! #V by 2 texture coordinates (u, v) as the file gives them, or no rows when it has none.
  //! A position on a UV seam has one render vertex per side, as on a crease.
  RowMatrixX2d uv;
  //! #V by 3 vertex colours, linear RGB in [0, 1] (decoded from the file's sRGB), or no rows
  //! when the file has none. Interpolated like UVs where refinement adds vertices.
  RowMatrixX3d colors;
  std::vector<Triangle> triangles;       //!< #F, render-vertex indices, counter-clockwise
  std::vector<uint32_t> source_face;     //!< #F, index of the input triangle it lies in
  size_t input_triangles = 0;            //!< triangles in the input after triangulation
  size_t input_vertices = 0;             //!< vertices as the file lists them
  bool normals_from_file = false;
  double crease_angle_deg = kDefaultCreaseAngleDeg;  //!< the crease angle computed normals used
  MeshDefects defects;

  bool has_uv() const { return uv.rows() > 0; }
  bool has_colors() const { return colors.rows() > 0; }

  size_t num_vertices() const { return vertex_position.size(); }
  size_t num_faces() const { return triangles.size(); }
  //! Position of render vertex v.
  Eigen::Vector3d point(uint32_t v) const { return positions.row(vertex_position[v]).transpose(); }
};

//! The sRGB decoding of an encoded value in [0, 1] to linear (IEC 61966-2-1).
double srgb_to_linear(double v);

//! Positions of render vertices: #V by 3.
RowMatrixX3d vertex_positions(const Mesh& mesh);

//! Axis-aligned bounds of the positions.
struct Bounds {
  Eigen::Vector3d lo, hi;
  Eigen::Vector3d centre() const { return 0.5 * (lo + hi); }
  double diagonal() const { return (hi - lo).norm(); }
};

//! \throw InputError when positions has no rows
Bounds bounds(const RowMatrixX3d& positions);

//! Area of triangle (a, b, c).
double triangle_area(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

struct EdgeAdjacency;

//! Edge statistics over positions: boundary, non-manifold and winding-conflict edge counts.
struct EdgeCounts {
  size_t boundary = 0, non_manifold = 0, winding_conflicts = 0, edges = 0;
};
//! \param triangles #F triangles indexing positions (not render vertices)
EdgeCounts count_edges(const std::vector<Triangle>& triangles);
//! The same from their edge_adjacency, if the caller has it.
EdgeCounts count_edges(const std::vector<Triangle>& triangles, const EdgeAdjacency& adjacency);

}  // namespace prtsub
