// Recording and replaying a bake's tracing calls, so that a bake can run as shards (each
// traces a slice of every call) and a merge (every call replayed from the slices): the same
// code runs, and the same numbers arrive where rays would have been traced.
#pragma once

#include <cstdint>
#include <vector>

#include "prtsub/prt/transfer.h"

namespace prtsub {

//! One tracing call's results over a slice of its points.
struct TraceCall {
  uint64_t fingerprint = 0;      //!< of the call's points, normals, offsets, groups and options
  uint64_t points = 0;           //!< the whole call's points
  uint64_t first = 0, last = 0;  //!< the slice [first, last)
  uint32_t values_per_point = 0;  //!< N²
  int rays = 0;                   //!< per point
  std::vector<double> values;     //!< (last − first) · N², row-major
  std::vector<double> variance;   //!< last − first
};

//! Thrown by a shard's bake when it has traced the phase it was given (not an error; bake_shard
//! catches it). nothing_left: the shard was given a phase after the last one.
struct PhaseDone {
  bool nothing_left = false;
};

//! The calls of a bake fall into phases, ended by barriers the pipeline places where what comes
//! next depends on what was traced (the pilot's second stage on its first; the fit's samples on
//! the pilot). Within a phase no call depends on another's results, so a shard can trace its
//! slice of each and carry on with zeros elsewhere, which nothing reads before the barrier.
//! Seeds are per point (its stream), so a slice is exactly those points' rows of the whole call.
class TraceLog {
 public:
  //! A shard: replays `done` (the phases before, each call gathered over every shard), then
  //! traces its slice of each call of the next phase: units (points, or groups of points) from
  //! ⌊U·index/count⌋ to ⌊U·(index+1)/count⌋, index 0-based.
  TraceLog(std::vector<std::vector<TraceCall>> done, uint32_t index, uint32_t count);
  //! A merge: replays every phase of `phases`; calls after the pipeline's last barrier (the
  //! error target's rounds) trace as usual.
  explicit TraceLog(std::vector<std::vector<TraceCall>> phases);

  enum class Action { Trace, Replay, Slice };
  struct Call {
    Action action = Action::Trace;
    const TraceCall* replay = nullptr;  //!< Replay: the gathered call
    uint64_t first = 0, last = 0;       //!< Slice: the units to trace
  };
  //! For the tracing functions: what to do with a call of `units` units.
  //! \throw InputError when a replayed call does not match (the parts are another bake's)
  Call begin(uint64_t fingerprint, uint64_t units);
  //! The slice a Slice call traced.
  void record(TraceCall call);

  //! For the pipeline: the end of a phase. `last`: the fit follows, and nothing more is sharded.
  //! \throw PhaseDone in a shard at the end of its phase; InputError when replayed phases do not
  //!        match the calls the pipeline made
  void barrier(bool last);

  size_t phase() const { return phase_; }  //!< phases passed so far
  bool past_last() const { return past_last_; }
  //! A shard's slices of its phase's calls.
  std::vector<TraceCall>& traced() { return traced_; }
  uint64_t traced_rays() const { return traced_rays_; }

 private:
  std::vector<std::vector<TraceCall>> replay_;
  bool shard_ = false, past_last_ = false;
  uint32_t index_ = 0, count_ = 1;
  size_t phase_ = 0, call_ = 0;
  std::vector<TraceCall> traced_;
  uint64_t traced_rays_ = 0;
};

//! XXH3 of what determines a call's results: points, normals, offsets, groups and the options
//! that choose rays (not the threads).
uint64_t trace_fingerprint(const RowMatrixX3d& points, const RowMatrixX3d& normals, const RowMatrixX3d* offsets,
                           const std::vector<size_t>* group_begin, const TransferOptions& options);

}  // namespace prtsub
