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

//! Entries grouped by a key with a counting sort: bucket b holds entry[begin[b] .. begin[b+1]), in
//! increasing entry order, entry = item·per_item + j. Linear in items and buckets; the same
//! grouping however it is later read, so what is built on it is deterministic.
struct Buckets {
  static constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> begin;  //!< buckets + 1
  std::vector<uint32_t> entry;
};

//! \param key key(item, j) for j < per_item: a bucket below `buckets`, or Buckets::kNone to leave the entry out
template <class Key>
Buckets bucket_sort(size_t buckets, size_t items, uint32_t per_item, Key&& key) {
  Buckets b;
  b.begin.assign(buckets + 1, 0);
  for (size_t i = 0; i < items; ++i)
    for (uint32_t j = 0; j < per_item; ++j)
      if (const uint32_t k = key(i, j); k != Buckets::kNone) ++b.begin[size_t(k) + 1];
  for (size_t k = 0; k < buckets; ++k) b.begin[k + 1] += b.begin[k];
  b.entry.resize(b.begin.back());
  std::vector<uint32_t> end(b.begin.begin(), b.begin.end() - 1);
  for (size_t i = 0; i < items; ++i)
    for (uint32_t j = 0; j < per_item; ++j)
      if (const uint32_t k = key(i, j); k != Buckets::kNone) b.entry[end[k]++] = static_cast<uint32_t>(i * per_item + j);
  return b;
}

//! Each vertex's corners 3f + c (face f = corner / 3), in increasing order.
inline Buckets vertex_corners(const std::vector<Triangle>& triangles, size_t vertices) {
  return bucket_sort(vertices, triangles.size(), 3, [&](size_t f, uint32_t c) { return triangles[f][c]; });
}

//! The vertices in breadth-first order over shared faces (each component from its lowest index):
//! neighbours get nearby ranks whatever the input's vertex order, so that arrays walked in this
//! order read their neighbours from cache (a scan's order, or a refined mesh's, can be far from
//! its faces'). \param corners vertex_corners(triangles, vertices)
inline std::vector<uint32_t> breadth_first_order(const std::vector<Triangle>& triangles, const Buckets& corners, size_t vertices) {
  std::vector<char> seen(vertices, 0);
  std::vector<uint32_t> queue;
  queue.reserve(vertices);
  size_t head = 0;
  for (uint32_t seed = 0; seed < vertices; ++seed) {
    if (seen[seed]) continue;
    seen[seed] = 1;
    queue.push_back(seed);
    for (; head < queue.size(); ++head)
      for (uint32_t k = corners.begin[queue[head]]; k < corners.begin[queue[head] + 1]; ++k)
        for (uint32_t u : triangles[corners.entry[k] / 3])
          if (!seen[u]) seen[u] = 1, queue.push_back(u);
  }
  return queue;
}

//! Vertex at the tail (corner k) and head (corner k+1) of half-edge h, through the map.
inline uint32_t half_edge_tail(const std::vector<Triangle>& t, uint32_t h) { return t[h / 3][h % 3]; }
inline uint32_t half_edge_head(const std::vector<Triangle>& t, uint32_t h) { return t[h / 3][(h % 3 + 1) % 3]; }

}  // namespace prtsub
