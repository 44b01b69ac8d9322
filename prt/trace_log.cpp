// A bake's tracing calls, recorded in slices and replayed (see trace_log.h). The pipeline makes
// its calls in an order that depends only on the mesh, the options and what earlier calls
// returned; replaying the earlier calls' exact results makes every later decision (the pilot's
// faces, the samples, the top-up plan) the same as in one process, so the merged asset is
// bit-identical. Each replayed call is checked against a fingerprint of its inputs: parts from
// another mesh, other options or another version of the pipeline are refused, never mixed in.
#include "prtsub/prt/trace_log.h"

#include <string>
#include <utility>

#include <xxhash.h>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

TraceLog::TraceLog(std::vector<std::vector<TraceCall>> done, uint32_t index, uint32_t count)
    : replay_(std::move(done)), shard_(true), index_(index), count_(count) {
  if (count == 0 || index >= count) throw InputError("shard " + std::to_string(index + 1) + " of " + std::to_string(count) + " does not exist");
}

TraceLog::TraceLog(std::vector<std::vector<TraceCall>> phases) : replay_(std::move(phases)) {}

TraceLog::Call TraceLog::begin(uint64_t fingerprint, uint64_t units) {
  Call c;
  if (past_last_) return c;
  const std::string where = "phase " + std::to_string(phase_ + 1) + ", call " + std::to_string(call_ + 1);
  if (phase_ < replay_.size()) {
    const std::vector<TraceCall>& calls = replay_[phase_];
    if (call_ >= calls.size() || calls[call_].fingerprint != fingerprint)
      throw InputError("the parts were traced for another bake (" + where + " differs): another mesh, other options or another prtsub");
    c.action = Action::Replay;
    c.replay = &calls[call_++];
    return c;
  }
  if (!shard_) throw InputError("the parts end before " + where + ": trace that phase's shards first");
  ++call_;
  c.action = Action::Slice;
  c.first = units * index_ / count_;
  c.last = units * (index_ + uint64_t(1)) / count_;
  return c;
}

void TraceLog::record(TraceCall call) {
  traced_rays_ += (call.last - call.first) * static_cast<uint64_t>(call.rays);
  traced_.push_back(std::move(call));
}

void TraceLog::barrier(bool last) {
  if (past_last_) return;
  if (phase_ < replay_.size()) {
    if (call_ != replay_[phase_].size())
      throw InputError("the parts were traced for another bake (phase " + std::to_string(phase_ + 1) + " has " +
                       std::to_string(replay_[phase_].size()) + " calls, this bake " + std::to_string(call_) + ")");
    ++phase_, call_ = 0;
    if (!last) return;
    if (phase_ < replay_.size()) throw InputError("the parts hold more phases than this bake has (" + std::to_string(phase_) + ")");
    if (shard_) throw PhaseDone{true};  // every phase is traced: the merge's turn
    past_last_ = true;
    return;
  }
  if (shard_) throw PhaseDone{false};
  throw InputError("the parts end before phase " + std::to_string(phase_ + 1) + ": trace that phase's shards first");
}

uint64_t trace_fingerprint(const RowMatrixX3d& points, const RowMatrixX3d& normals, const RowMatrixX3d* offsets,
                           const std::vector<size_t>* group_begin, const TransferOptions& o) {
  XXH3_state_t* state = XXH3_createState();
  if (!state) throw Error("transfer: cannot allocate a hash state");
  XXH3_64bits_reset(state);
  auto add = [&](const void* data, size_t bytes) { XXH3_64bits_update(state, data, bytes); };
  const uint64_t head[] = {uint64_t(points.rows()), uint64_t(o.order), uint64_t(o.rays), o.seed, o.stream_offset, o.first_ray,
                           uint64_t(o.first_round_rays), offsets ? 1u : 0u, group_begin ? group_begin->size() : 0,
                           o.streams ? o.streams->size() : 0};
  add(head, sizeof head);
  if (o.estimator != TransferEstimator::ControlVariate) {  // the default's fingerprints stay as they were
    const double encoder[] = {double(o.estimator), o.progressive.acceleration, double(o.progressive.gauss_seidel),
                              double(o.progressive.denominator)};
    add(encoder, sizeof encoder);
  }
  add(points.data(), sizeof(double) * size_t(points.size()));
  add(normals.data(), sizeof(double) * size_t(normals.size()));
  if (offsets) add(offsets->data(), sizeof(double) * size_t(offsets->size()));
  if (group_begin) add(group_begin->data(), sizeof(size_t) * group_begin->size());
  if (o.streams) add(o.streams->data(), sizeof(uint64_t) * o.streams->size());
  const uint64_t h = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  return h;
}

}  // namespace prtsub
