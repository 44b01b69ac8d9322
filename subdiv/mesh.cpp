#include "subdiv/mesh.h"

#include <algorithm>

namespace prtsub {

RowMatrixX3d vertex_positions(const Mesh& mesh) {
  RowMatrixX3d p(static_cast<Eigen::Index>(mesh.num_vertices()), 3);
  for (size_t v = 0; v < mesh.num_vertices(); ++v) p.row(static_cast<Eigen::Index>(v)) = mesh.positions.row(mesh.vertex_position[v]);
  return p;
}

Bounds bounds(const RowMatrixX3d& positions) {
  Bounds b;
  b.lo = positions.colwise().minCoeff().transpose();
  b.hi = positions.colwise().maxCoeff().transpose();
  return b;
}

double triangle_area(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

EdgeCounts count_edges(const std::vector<Triangle>& triangles) {
  // Sort directed half-edges by their undirected key; each run is one edge.
  struct HalfEdge {
    uint64_t key;
    bool forward;
  };
  std::vector<HalfEdge> half;
  half.reserve(triangles.size() * 3);
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      uint32_t lo = std::min(a, b), hi = std::max(a, b);
      half.push_back({(uint64_t(lo) << 32) | hi, a < b});
    }
  }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key < y.key || (x.key == y.key && x.forward < y.forward);
  });
  EdgeCounts counts;
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    size_t n = j - i;
    ++counts.edges;
    if (n == 1) ++counts.boundary;
    if (n > 2) ++counts.non_manifold;
    if (n == 2 && half[i].forward == half[i + 1].forward) ++counts.winding_conflicts;
    i = j;
  }
  return counts;
}

}  // namespace prtsub
