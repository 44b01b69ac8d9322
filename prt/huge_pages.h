// Large arrays a stage writes once and then reads a few times (the fit's system and right-hand
// sides, block CG's vectors) cost most of their time in first-touch page faults where faults
// are dear, as on our 2-core virtual machine: 31% of a `prtsub bench --solve` profile on
// armadillo was the kernel's fault handler (BENCHMARKS.md, "The solve"). Asking the kernel for
// transparent huge pages on such an array, before it is first written, takes 512 times fewer
// faults. It is only advice: where huge pages are off (transparent_hugepage "never") nothing
// changes, and the values never depend on it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace prtsub {

//! Advises huge pages for the whole 2 MiB pages inside [p, p + bytes); call it before the first write.
inline void prefer_huge_pages(void* p, size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  if (!p || bytes < 2 * kHuge) return;
  const uintptr_t first = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t last = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);  // (a hint: its failure changes nothing)
#else
  (void)p, (void)bytes;
#endif
}

//! The same for a dense Eigen matrix's storage.
template <class Matrix>
void prefer_huge_pages(Matrix& m) {
  prefer_huge_pages(static_cast<void*>(m.data()), static_cast<size_t>(m.size()) * sizeof(typename Matrix::Scalar));
}

//! std::allocator that advises huge pages on each allocation before its elements are constructed.
template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}
  T* allocate(size_t n) {
    T* p = std::allocator<T>().allocate(n);
    prefer_huge_pages(p, n * sizeof(T));
    return p;
  }
  void deallocate(T* p, size_t n) { std::allocator<T>().deallocate(p, n); }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
  template <class U>
  bool operator!=(const HugePageAllocator<U>&) const { return false; }
};
template <class T>
using HugeVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace prtsub
