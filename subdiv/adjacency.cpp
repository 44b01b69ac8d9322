// Half-edges sorted by (undirected key, index): each run of equal keys is one edge. A sort of
// 3F 12-byte records beats a hash table here (no per-edge allocation, and the runs come out in
// a fixed order, so everything built on them is deterministic).
#include "prtsub/subdiv/adjacency.h"

#include <algorithm>

namespace prtsub {

EdgeAdjacency edge_adjacency(const std::vector<Triangle>& triangles, const std::vector<uint32_t>* vertex_map) {
  const size_t H = triangles.size() * 3;
  std::vector<std::pair<uint64_t, uint32_t>> half;
  half.reserve(H);
  auto map = [&](uint32_t v) { return vertex_map ? (*vertex_map)[v] : v; };
  for (uint32_t f = 0; f < triangles.size(); ++f)
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t a = map(triangles[f][k]), b = map(triangles[f][(k + 1) % 3]);
      if (a == b) continue;
      half.emplace_back((uint64_t(std::min(a, b)) << 32) | std::max(a, b), 3 * f + k);
    }
  std::sort(half.begin(), half.end());
  EdgeAdjacency adj;
  adj.edge_of.assign(H, EdgeAdjacency::kNone);
  adj.half_edges.resize(half.size());
  adj.begin.reserve(half.size() / 2 + 2);
  for (size_t r = 0; r < half.size(); ++r) {
    if (r == 0 || half[r].first != half[r - 1].first) adj.begin.push_back(static_cast<uint32_t>(r));
    adj.half_edges[r] = half[r].second;
    adj.edge_of[half[r].second] = static_cast<uint32_t>(adj.begin.size() - 1);
  }
  adj.begin.push_back(static_cast<uint32_t>(half.size()));
  return adj;
}

}  // namespace prtsub
