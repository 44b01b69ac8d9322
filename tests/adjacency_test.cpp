#include "prtsub/subdiv/adjacency.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "helpers.h"
#include "prtsub/subdiv/random.h"

namespace prtsub {
namespace {

TEST(Adjacency, ClosedCubeHasEighteenTwoFacedEdgesWithOppositeHalfEdges) {
  const Mesh cube = test::build(test::cube());
  const EdgeAdjacency adj = edge_adjacency(cube.triangles, &cube.vertex_position);
  ASSERT_EQ(adj.num_edges(), 18u);  // V − E + F = 2 with V = 8, F = 12
  for (size_t e = 0; e < adj.num_edges(); ++e) {
    ASSERT_EQ(adj.valence(e), 2u);
    const uint32_t* h = adj.edge_begin(e);
    EXPECT_LT(h[0], h[1]);  // in increasing order
    const auto pos = [&](uint32_t v) { return cube.vertex_position[v]; };
    // Consistent winding: the two sides run the edge in opposite directions.
    EXPECT_EQ(pos(half_edge_tail(cube.triangles, h[0])), pos(half_edge_head(cube.triangles, h[1])));
    EXPECT_EQ(pos(half_edge_head(cube.triangles, h[0])), pos(half_edge_tail(cube.triangles, h[1])));
    EXPECT_EQ(adj.edge_of[h[0]], e);
    EXPECT_EQ(adj.edge_of[h[1]], e);
  }
  // Without the map, the cube's creases split every edge into render-vertex edges of one face.
  const EdgeAdjacency render = edge_adjacency(cube.triangles);
  EXPECT_EQ(render.num_edges(), 30u);  // 12 diagonals shared within a side, 18 crease edges twice
}

TEST(Adjacency, BoundaryFinsAndCollapsedHalfEdges) {
  // Two triangles on edge {0,1}, a fin on the same edge, and a face whose corners 3 and 4 map
  // to one vertex.
  const std::vector<Triangle> t = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {5, 6, 7}};
  const std::vector<uint32_t> map = {0, 1, 2, 3, 4, 5, 6, 6};
  const EdgeAdjacency adj = edge_adjacency(t, &map);
  const uint32_t shared = adj.edge_of[0];
  EXPECT_EQ(adj.valence(shared), 3u);
  EXPECT_EQ(adj.edge_of[3], shared);
  EXPECT_EQ(adj.edge_of[6], shared);
  EXPECT_EQ(adj.edge_of[10], EdgeAdjacency::kNone);  // 6 -> 7 maps to 6 -> 6
  EXPECT_NE(adj.edge_of[9], EdgeAdjacency::kNone);
  EXPECT_EQ(adj.edge_of[9], adj.edge_of[11]);  // 5-6 and 7-5 are 5-6 and 6-5 after the map
  EXPECT_EQ(adj.valence(adj.edge_of[9]), 2u);
  size_t boundary = 0;
  for (size_t e = 0; e < adj.num_edges(); ++e) boundary += adj.valence(e) == 1;
  EXPECT_EQ(boundary, 6u);  // 1-2, 2-0, 0-3, 3-1, 1-4, 4-0
  const EdgeCounts counts = count_edges(t);  // unmapped: 6-7 is a real edge there
  EXPECT_EQ(counts.non_manifold, 1u);
  EXPECT_EQ(counts.boundary, 9u);
  EXPECT_EQ(counts.winding_conflicts, 0u);
}

TEST(Adjacency, EdgesAreInKeyOrderWithTheirHalfEdgesAscendingOnAnySoup) {
  // Random soups with repeated, collapsed and non-manifold faces, with and without a vertex map:
  // edges come in increasing (min, max) order, each with its half-edges in increasing order, and
  // edge_of inverts it: the order every algorithm built on it relies on for determinism.
  Rng rng(7, 0);
  for (int trial = 0; trial < 20; ++trial) {
    const uint32_t V = 3 + uint32_t(rng.next() % 40);
    std::vector<Triangle> t(1 + rng.next() % 200);
    for (Triangle& tri : t)
      for (uint32_t& v : tri) v = uint32_t(rng.next() % V);
    std::vector<uint32_t> map(V);
    for (uint32_t& m : map) m = uint32_t(rng.next() % V);
    const std::vector<uint32_t>* maps[] = {nullptr, &map};
    for (const std::vector<uint32_t>* vm : maps) {
      auto at = [&](uint32_t v) { return vm ? (*vm)[v] : v; };
      std::vector<std::pair<uint64_t, uint32_t>> expected;  // the plain way: sort (key, half-edge)
      for (uint32_t h = 0; h < 3 * t.size(); ++h) {
        const uint32_t a = at(half_edge_tail(t, h)), b = at(half_edge_head(t, h));
        if (a != b) expected.emplace_back((uint64_t(std::min(a, b)) << 32) | std::max(a, b), h);
      }
      std::sort(expected.begin(), expected.end());
      const EdgeAdjacency adj = edge_adjacency(t, vm);
      ASSERT_EQ(adj.half_edges.size(), expected.size());
      size_t edges = 0;
      for (size_t r = 0; r < expected.size(); ++r) {
        edges += r == 0 || expected[r].first != expected[r - 1].first;
        EXPECT_EQ(adj.half_edges[r], expected[r].second);
        EXPECT_EQ(adj.edge_of[expected[r].second], edges - 1);
      }
      EXPECT_EQ(adj.num_edges(), edges);
      for (uint32_t h = 0; h < 3 * t.size(); ++h) {
        if (at(half_edge_tail(t, h)) == at(half_edge_head(t, h))) {
          EXPECT_EQ(adj.edge_of[h], EdgeAdjacency::kNone);
        }
      }
    }
  }
}

TEST(Adjacency, WindingConflictsAreCounted) {
  EXPECT_EQ(count_edges({{0, 1, 2}, {0, 1, 3}}).winding_conflicts, 1u);
  EXPECT_EQ(count_edges({{0, 1, 2}, {1, 0, 3}}).winding_conflicts, 0u);
}

}  // namespace
}  // namespace prtsub
