#include "prtsub/subdiv/mesh.h"

#include "prtsub/subdiv/adjacency.h"
#include "prtsub/subdiv/exceptions.h"

#include <algorithm>

#include <cmath>

namespace prtsub {

double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

RowMatrixX3d vertex_positions(const Mesh& mesh) {
  RowMatrixX3d p(static_cast<Eigen::Index>(mesh.num_vertices()), 3);
  for (size_t v = 0; v < mesh.num_vertices(); ++v) p.row(static_cast<Eigen::Index>(v)) = mesh.positions.row(mesh.vertex_position[v]);
  return p;
}

Bounds bounds(const RowMatrixX3d& positions) {
  if (positions.rows() == 0) throw InputError("bounds of an empty point set");
  Bounds b;
  b.lo = positions.colwise().minCoeff().transpose();
  b.hi = positions.colwise().maxCoeff().transpose();
  return b;
}

double triangle_area(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

EdgeCounts count_edges(const std::vector<Triangle>& triangles) { return count_edges(triangles, edge_adjacency(triangles)); }

EdgeCounts count_edges(const std::vector<Triangle>& triangles, const EdgeAdjacency& adj) {
  EdgeCounts counts;
  counts.edges = adj.num_edges();
  for (size_t e = 0; e < adj.num_edges(); ++e) {
    const uint32_t n = adj.valence(e);
    if (n == 1) ++counts.boundary;
    if (n > 2) ++counts.non_manifold;
    // Two faces that agree in winding run the edge in opposite directions: different tails.
    const uint32_t* h = adj.edge_begin(e);
    if (n == 2 && half_edge_tail(triangles, h[0]) == half_edge_tail(triangles, h[1])) ++counts.winding_conflicts;
  }
  return counts;
}

}  // namespace prtsub
