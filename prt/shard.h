// A bake of a fixed mesh in shards and a merge (docs/scaling.md, "Shards"): each shard traces
// a slice of the vertices' and the samples' rays into a part file; the merge gathers the parts,
// runs the fit and gives the asset a single process would have written, bit for bit.
//
//   prtsub::ShardOptions s;  s.shard = 2; s.shards = 4; s.dir = "parts"; s.key = key;
//   prtsub::bake_shard(mesh, options, s);                 // per shard, per phase
//   prtsub::BakeResult r = prtsub::bake_merged(mesh, options, "parts", key);
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "prtsub/prt/bake.h"
#include "prtsub/prt/trace_log.h"

namespace prtsub {

struct ShardOptions {
  uint32_t shard = 1, shards = 1;  //!< this shard, 1-based, of `shards`
  //! 1-based; 0: the first phase this shard has no part of. Phase q needs every shard's part of
  //! the phases before it.
  int phase = 0;
  std::string dir;  //!< where the parts are read and written (created if missing)
  //! the bake's content key (bake_key of the input and the options): parts with another are refused
  std::string key;
  //! written into each part's header: the tool records the input and its options, so that a
  //! merge needs only the folder
  std::vector<std::pair<std::string, std::string>> notes;
};

//! "i/N" with 1 ≤ i ≤ N ≤ 65536. \throw InputError otherwise
std::pair<uint32_t, uint32_t> parse_shard(const std::string& text);

//! How many phases a sharded bake with these options has: 1 for point values or area samples,
//! 2 with a one-stage pilot, 3 with the default two-stage pilot (its second stage depends on the
//! first, the samples on both).
int shard_phases(const BakeOptions& options);

struct ShardResult {
  int phase = 0, phases = 0;  //!< the phase traced (1-based), of the bake's phases
  bool nothing_left = false;  //!< this shard had traced every phase: the merge's turn
  std::string path;           //!< the part written
  uint64_t rays = 0;          //!< traced by this shard in this phase
  uint64_t points = 0;        //!< points traced
  size_t bytes = 0;           //!< the part's size
  double seconds = 0;
};

//! One shard's slice of one phase, written to `dir` as phaseQ-shardIofN.part (atomically).
//! The mesh must be fixed (no adaptive refinement: bake with refine_only first).
//! \throw InputError for parts of another bake or count, a duplicated or missing earlier part
ShardResult bake_shard(const Mesh& mesh, const BakeOptions& options, const ShardOptions& shard, const BakeProgress& progress = {});

//! The bake, its rays replayed from every part in `dir`: the result bake() gives, bit for bit.
//! What the pipeline does after its last phase (the fit, --error's rounds, bounces) runs here.
//! \throw InputError for missing, duplicated, mismatched or damaged parts, each named
BakeResult bake_merged(const Mesh& mesh, const BakeOptions& options, const std::string& dir, const std::string& key,
                       const BakeProgress& progress = {});

struct PartHeader {
  std::string path, key;
  uint32_t shard = 0, shards = 0, phase = 0;  //!< 1-based
  std::vector<std::pair<std::string, std::string>> notes;
};
//! A whole part: its header and its calls' slices (trace_log.h).
struct Part {
  PartHeader header;
  std::vector<TraceCall> calls;
};
//! A part from its bytes, every size and the checksum checked. \throw InputError naming `path`
Part parse_part(const std::string& bytes, const std::string& path);

//! The header of a part file. \throw IoError if unreadable, InputError if not a part
PartHeader read_part_header(const std::string& path);
//! The headers of every *.part file in `dir`, in name order. \throw IoError if dir is not a folder
std::vector<PartHeader> list_parts(const std::string& dir);

}  // namespace prtsub
