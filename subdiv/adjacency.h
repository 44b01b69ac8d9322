// Edges of a triangle list, the one adjacency every algorithm in prtsub starts from (defect
// counts, crease-aware normals, refinement's corner links, the fit's regulariser, OpenSubdiv's
// crease tags).
#pragma once

#include <cstdint>
#include <vector>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

//! Half-edge h = 3f + k runs from corner k to corner k+1 of face f. Half-edges are grouped by
//! the undirected edge {a, b} of the (mapped) vertices they join: edge e's half-edges are
//! half_edges[begin[e] .. begin[e+1]), in increasing order of h. One half-edge: a boundary;
//! two: a manifold edge (in either winding); more: non-manifold. A half-edge whose ends map to
//! the same vertex belongs to no edge.
struct EdgeAdjacency {
  static constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> begin;       //!< #E + 1
  std::vector<uint32_t> half_edges;  //!< grouped by edge
  std::vector<uint32_t> edge_of;     //!< #3F: the edge of each half-edge, or kNone

  size_t num_edges() const { return begin.empty() ? 0 : begin.size() - 1; }
  //! Number of faces on edge e (counting a face twice if it has the edge twice).
  uint32_t valence(size_t e) const { return begin[e + 1] - begin[e]; }
  const uint32_t* edge_begin(size_t e) const { return half_edges.data() + begin[e]; }
};

//! \param triangles #F triangles
//! \param vertex_map if given, maps every index of `triangles` to the vertex edges are taken
//!        over (a mesh's render vertices to their welded positions); null: the indices themselves
EdgeAdjacency edge_adjacency(const std::vector<Triangle>& triangles, const std::vector<uint32_t>* vertex_map = nullptr);

//! Vertex at the tail (corner k) and head (corner k+1) of half-edge h, through the map.
inline uint32_t half_edge_tail(const std::vector<Triangle>& t, uint32_t h) { return t[h / 3][h % 3]; }
inline uint32_t half_edge_head(const std::vector<Triangle>& t, uint32_t h) { return t[h / 3][(h % 3 + 1) % 3]; }

}  // namespace prtsub
