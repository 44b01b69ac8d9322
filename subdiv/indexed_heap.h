// A binary max-heap of ids whose keys can be updated or removed in O(log n): each id's slot
// in the heap is stored beside it. Ties are broken by the smaller id, so the order of pops
// is a function of the keys alone (deterministic refinement).
#pragma once

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <utility>
#include <vector>

namespace prtsub {

template <class Key>
class IndexedHeap {
 public:
  //! Room for ids below n without reallocation.
  void reserve(size_t n) {
    heap_.reserve(n);
    if (slot_.size() < n) slot_.resize(n, kAbsent), keys_.resize(n);
  }
  bool empty() const { return heap_.empty(); }
  size_t size() const { return heap_.size(); }
  bool contains(uint32_t id) const { return id < slot_.size() && slot_[id] != kAbsent; }
  const Key& key(uint32_t id) const { return keys_[id]; }
  uint32_t top() const { return heap_.front(); }

  //! Inserts id, or updates its key if present.
  void push(uint32_t id, const Key& key) {
    if (id >= slot_.size()) {
      slot_.resize(std::max<size_t>(id + 1, 2 * slot_.size()), kAbsent);
      keys_.resize(slot_.size());
    }
    keys_[id] = key;
    if (slot_[id] == kAbsent) {
      slot_[id] = static_cast<uint32_t>(heap_.size());
      heap_.push_back(id);
      up(slot_[id]);
    } else {
      up(slot_[id]);
      down(slot_[id]);
    }
  }

  uint32_t pop() {
    uint32_t id = heap_.front();
    remove(id);
    return id;
  }

  void remove(uint32_t id) {
    if (!contains(id)) return;
    uint32_t s = slot_[id];
    swap_slots(s, static_cast<uint32_t>(heap_.size() - 1));
    heap_.pop_back();
    slot_[id] = kAbsent;
    if (s < heap_.size()) {
      up(s);
      down(s);
    }
  }

 private:
  static constexpr uint32_t kAbsent = UINT32_MAX;
  bool before(uint32_t a, uint32_t b) const {  // a ranks above b
    return keys_[a] > keys_[b] || (!(keys_[b] > keys_[a]) && a < b);
  }
  void swap_slots(uint32_t i, uint32_t j) {
    std::swap(heap_[i], heap_[j]);
    slot_[heap_[i]] = i;
    slot_[heap_[j]] = j;
  }
  void up(uint32_t i) {
    while (i > 0) {
      uint32_t p = (i - 1) / 2;
      if (!before(heap_[i], heap_[p])) break;
      swap_slots(i, p);
      i = p;
    }
  }
  void down(uint32_t i) {
    for (;;) {
      uint32_t l = 2 * i + 1, r = l + 1, best = i;
      if (l < heap_.size() && before(heap_[l], heap_[best])) best = l;
      if (r < heap_.size() && before(heap_[r], heap_[best])) best = r;
      if (best == i) return;
      swap_slots(i, best);
      i = best;
    }
  }
  std::vector<uint32_t> heap_;
  std::vector<uint32_t> slot_;
  std::vector<Key> keys_;
};

}  // namespace prtsub
