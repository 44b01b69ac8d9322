// The one way prt/ spreads a loop over the cores: TBB on `threads` workers (0: every core).
// Results never depend on the thread count; callers keep their reductions in a fixed order.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace prtsub {

//! body(tbb::blocked_range<Index>) over [0, count), in chunks of at least `grain`.
template <class Index, class Body>
void parallel_range(Index count, int threads, Index grain, Body&& body) {
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] { tbb::parallel_for(tbb::blocked_range<Index>(0, count, grain), body); });
}

}  // namespace prtsub
