// Many bakes in one process (docs/batch.md): the jobs share the process's Embree device and TBB
// thread pool, each fails alone, and an asset already baked from the same input bytes with the
// same options is skipped, by a content key stored in its metadata.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "prtsub/prt/bake.h"
#include "prtsub/prt/gltf.h"
#include "prtsub/subdiv/mesh_io.h"

namespace prtsub {

struct BatchJob {
  std::string input;   //!< a mesh file
  std::string output;  //!< the asset: .ply, .glb or .gltf
};

struct BatchOptions {
  BakeOptions bake;  //!< every job's bake (source is set per job)
  LoadOptions load;
  GltfOptions gltf;  //!< for .glb and .gltf outputs
  bool force = false;  //!< bake even when the output is up to date
};

enum class BatchStatus { Baked, Skipped, Failed };
const char* batch_status_name(BatchStatus s);

struct BatchEntry {
  BatchJob job;
  BatchStatus status = BatchStatus::Failed;
  std::string error;  //!< Failed: the one-line reason (it names the file)
  std::string key;    //!< the content key (empty when the input could not be read)
  size_t triangles_in = 0, triangles_out = 0, vertices_out = 0;
  uint64_t rays = 0;
  double seconds = 0;  //!< load, bake and write (or the key check, when skipped)
};

struct BatchProgress {
  std::function<void(size_t index, size_t total, const BatchJob& job)> start;
  //! `result` is the bake (null unless it baked): what a report of the job is made from
  std::function<void(size_t index, size_t total, const BatchEntry& entry, const BakeResult* result)> done;
  BakeProgress bake;  //!< each bake's stages
};

//! The jobs for `inputs` (mesh files; directories, searched recursively for .obj, .ply, .off and
//! .stl in name order; or "@LIST", a text file of one path per line, relative to the list's
//! folder, blank lines and lines starting with # skipped), each written to `out_dir` as its
//! name with `extension` (".ply", ".glb" or ".gltf"), keeping the folders below a directory.
//! \throw InputError for a missing input, an unknown extension or two jobs writing one asset
std::vector<BatchJob> batch_jobs(const std::vector<std::string>& inputs, const std::string& out_dir, const std::string& extension);

//! The content key of a bake: a 128-bit XXH3 hash, in hex, of the input's bytes, every option
//! that changes the asset (not the thread count, which does not), the output's format and the
//! library's version.
std::string bake_key(const std::string& input_bytes, const BatchOptions& options, const std::string& output);

//! The key recorded in an asset ("bake_key" in its metadata), or "" when the file is missing,
//! unreadable or has none.
std::string asset_bake_key(const std::string& path);

//! Runs the jobs in order. A job that fails (any prtsub::Error: bad input, IO, Embree, the
//! solver) is recorded with its one-line reason and the next one runs; nothing else is caught
//! (out of memory ends the batch). Outputs' folders are created.
std::vector<BatchEntry> bake_batch(const std::vector<BatchJob>& jobs, const BatchOptions& options, const BatchProgress& progress = {});

}  // namespace prtsub
