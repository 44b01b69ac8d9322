// Per-corner normals with a crease angle: faces around a position that meet across a
// smooth edge share one normal; across a crease each side keeps its own.
#pragma once

#include <vector>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

struct EdgeAdjacency;

struct CornerNormals {
  RowMatrixX3d normals;         //!< #G by 3, one unit normal per smoothing group
  std::vector<uint32_t> group;  //!< #F*3, smoothing group of corner 3f+k
  size_t fallback_normals = 0;  //!< groups whose faces all have zero area (normal guessed)
};

//! Angle-weighted normals, smoothed across edges whose faces' normals differ by at most
//! `crease_angle_deg`. Non-manifold edges and edges whose faces disagree in winding are
//! always creases. Groups are numbered in order of their first corner.
//! \param positions #P by 3
//! \param triangles #F triangles indexing positions
//! \param adjacency the triangles' edge_adjacency, if the caller has it (null: built here)
CornerNormals compute_corner_normals(const RowMatrixX3d& positions,
                                     const std::vector<Triangle>& triangles,
                                     double crease_angle_deg, const EdgeAdjacency* adjacency = nullptr);

}  // namespace prtsub
