// Half-edges sorted by (undirected key {a < b}, index): each run of equal keys is one edge, in a
// fixed order, so everything built on them is deterministic. The sort is a counting sort by a
// (stable, so each bucket keeps increasing half-edge order) and then an insertion sort by b
// within each bucket (a vertex's edges: a handful): linear, and no per-edge allocation.
#include "prtsub/subdiv/adjacency.h"

#include <algorithm>

namespace prtsub {

EdgeAdjacency edge_adjacency(const std::vector<Triangle>& triangles, const std::vector<uint32_t>* vertex_map) {
  const size_t H = triangles.size() * 3;
  auto map = [&](uint32_t v) { return vertex_map ? (*vertex_map)[v] : v; };
  uint32_t vertices = 0;
  for (const Triangle& t : triangles)
    for (uint32_t v : t) vertices = std::max(vertices, map(v) + 1);
  std::vector<uint32_t> begin(size_t(vertices) + 1, 0);
  auto ends = [&](uint32_t h) {
    const uint32_t a = map(triangles[h / 3][h % 3]), b = map(triangles[h / 3][(h % 3 + 1) % 3]);
    return std::make_pair(std::min(a, b), std::max(a, b));
  };
  for (uint32_t h = 0; h < H; ++h) {
    const auto [a, b] = ends(h);
    if (a != b) ++begin[a + 1];
  }
  for (size_t v = 0; v < vertices; ++v) begin[v + 1] += begin[v];
  struct Half {
    uint32_t b, h;
  };
  std::vector<Half> half(begin.back());
  {
    std::vector<uint32_t> end(begin.begin(), begin.end() - 1);
    for (uint32_t h = 0; h < H; ++h) {
      const auto [a, b] = ends(h);
      if (a != b) half[end[a]++] = {b, h};
    }
  }
  for (size_t v = 0; v < vertices; ++v)  // stable: equal b keep their increasing h
    for (uint32_t i = begin[v] + 1; i < begin[v + 1]; ++i)
      for (uint32_t j = i; j > begin[v] && half[j - 1].b > half[j].b; --j) std::swap(half[j - 1], half[j]);
  EdgeAdjacency adj;
  adj.edge_of.assign(H, EdgeAdjacency::kNone);
  adj.half_edges.resize(half.size());
  adj.begin.reserve(half.size() / 2 + 2);
  uint32_t a = 0;
  for (uint32_t r = 0; r < half.size(); ++r) {
    while (begin[a + 1] <= r) ++a;  // the bucket of r
    if (r == begin[a] || half[r].b != half[r - 1].b) adj.begin.push_back(r);
    adj.half_edges[r] = half[r].h;
    adj.edge_of[half[r].h] = static_cast<uint32_t>(adj.begin.size() - 1);
  }
  adj.begin.push_back(static_cast<uint32_t>(half.size()));
  return adj;
}

}  // namespace prtsub
