// A flat hash table from 64-bit edge keys to small values, for refinement's edge-to-face map.
// Open addressing with linear probing in one contiguous array, and backward-shift deletion (no
// tombstones), so lookups touch one or two cache lines. std::unordered_map's node per entry
// made refinement's time grow faster than T log T once the map outgrew the cache.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <vector>

namespace prtsub {

template <class Value>
class EdgeTable {
 public:
  explicit EdgeTable(size_t expected = 16) { rehash(expected * 2); }

  size_t size() const { return size_; }

  //! Room for n entries without rehashing.
  void reserve(size_t n) {
    if (n * 4 > slots_.size() * 3) rehash(n * 4 / 3 + 1);
  }

  //! The value of key, inserted default-constructed if absent.
  Value& operator[](uint64_t key) {
    if ((size_ + 1) * 4 > slots_.size() * 3) rehash(slots_.size() * 2);  // load <= 3/4
    size_t i = find_slot(key);
    if (!slots_[i].used) {
      slots_[i] = Slot{key, Value{}, true};
      ++size_;
    }
    return slots_[i].value;
  }

  //! \throw std::out_of_range if absent
  Value& at(uint64_t key) {
    size_t i = find_slot(key);
    if (!slots_[i].used) throw std::out_of_range("edge not found");
    return slots_[i].value;
  }
  const Value& at(uint64_t key) const { return const_cast<EdgeTable*>(this)->at(key); }

  void erase(uint64_t key) {
    size_t i = find_slot(key);
    if (!slots_[i].used) return;
    // Backward-shift: move later entries of the probe run into the hole.
    size_t hole = i;
    for (size_t j = (i + 1) & mask_;; j = (j + 1) & mask_) {
      if (!slots_[j].used) break;
      size_t home = hash(slots_[j].key) & mask_;
      // Entry j may fill the hole if its home is not in (hole, j] cyclically.
      bool movable = hole <= j ? (home <= hole || home > j) : (home <= hole && home > j);
      if (movable) {
        slots_[hole] = slots_[j];
        hole = j;
      }
    }
    slots_[hole].used = false;
    --size_;
  }

  template <class F>
  void for_each(F&& f) const {
    for (const Slot& s : slots_)
      if (s.used) f(s.key, s.value);
  }

 private:
  struct Slot {
    uint64_t key = 0;
    Value value{};
    bool used = false;
  };
  static size_t hash(uint64_t k) {
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdull;
    k ^= k >> 33;
    return static_cast<size_t>(k);
  }
  size_t find_slot(uint64_t key) const {
    size_t i = hash(key) & mask_;
    while (slots_[i].used && slots_[i].key != key) i = (i + 1) & mask_;
    return i;
  }
  void rehash(size_t want) {
    size_t n = 16;
    while (n < want) n *= 2;
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(n, Slot{});
    mask_ = n - 1;
    size_ = 0;
    for (const Slot& s : old)
      if (s.used) (*this)[s.key] = s.value;
  }
  std::vector<Slot> slots_;
  size_t mask_ = 0, size_ = 0;
};

}  // namespace prtsub
