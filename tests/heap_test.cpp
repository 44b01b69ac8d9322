// The refinement queue against a reference container under random operations.
#include "prtsub/subdiv/indexed_heap.h"

#include <gtest/gtest.h>

#include <map>
#include <set>

#include "prtsub/subdiv/random.h"

namespace prtsub {
namespace {

TEST(IndexedHeap, PopsByKeyThenIdAndSupportsUpdateAndRemove) {
  IndexedHeap<std::pair<double, double>> h;
  h.push(3, {1, 0});
  h.push(1, {5, 0});
  h.push(7, {5, 0});
  h.push(2, {0, 9});
  h.push(3, {6, 0});  // update up
  h.push(1, {-1, 0});  // update down
  h.remove(7);
  h.remove(42);  // absent: no-op
  std::vector<uint32_t> order;
  while (!h.empty()) order.push_back(h.pop());
  EXPECT_EQ(order, (std::vector<uint32_t>{3, 2, 1}));
}

// The reference: a std::set ordered as the heap promises (larger key first, then smaller id),
// beside the current key of every id. Keys come from a small range, so ties are common.
TEST(IndexedHeap, MatchesAReferenceUnderRandomPushUpdateRemoveAndPop) {
  using Key = std::pair<double, double>;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    Rng rng(seed, 1);
    IndexedHeap<Key> heap;
    std::map<uint32_t, Key> key_of;
    std::set<std::pair<Key, int64_t>> order;  // (key, -id): the last element is the top
    if (seed % 2) heap.reserve(16);
    size_t pops = 0;
    for (int op = 0; op < 4000; ++op) {
      const uint32_t id = static_cast<uint32_t>(rng.next() % 200);
      const uint64_t what = rng.next() % 10;
      if (what < 5) {  // push or update
        const Key k{static_cast<double>(rng.next() % 8), static_cast<double>(rng.next() % 3)};
        if (key_of.count(id)) order.erase({key_of[id], -int64_t(id)});
        key_of[id] = k;
        order.insert({k, -int64_t(id)});
        heap.push(id, k);
      } else if (what < 7) {  // remove, present or not
        if (key_of.count(id)) order.erase({key_of[id], -int64_t(id)}), key_of.erase(id);
        heap.remove(id);
      } else if (!order.empty()) {  // pop
        const uint32_t expected = static_cast<uint32_t>(-std::prev(order.end())->second);
        ASSERT_EQ(heap.top(), expected) << "seed " << seed << ", operation " << op;
        ASSERT_EQ(heap.pop(), expected);
        order.erase(std::prev(order.end()));
        key_of.erase(expected);
        ++pops;
      }
      ASSERT_EQ(heap.size(), order.size());
      ASSERT_EQ(heap.contains(id), key_of.count(id) == 1);
      if (key_of.count(id)) {
        ASSERT_EQ(heap.key(id), key_of[id]);
      }
    }
    EXPECT_GT(pops, 500u);  // the sequence exercised pops, not only pushes
    while (!order.empty()) {
      ASSERT_EQ(heap.pop(), static_cast<uint32_t>(-std::prev(order.end())->second));
      order.erase(std::prev(order.end()));
    }
    EXPECT_TRUE(heap.empty());
  }
}

}  // namespace
}  // namespace prtsub
