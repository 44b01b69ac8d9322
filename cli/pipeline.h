// The bake pipeline as one function: mesh -> (uniform refinement) -> transfer -> (adaptive
// refinement) -> asset data. `bake` writes its result; `compare` runs it many times.
#pragma once

#include <string>

#include "prt/asset.h"
#include "prt/refine_signal.h"
#include "subdiv/mesh_io.h"
#include "subdiv/refine.h"
#include "subdiv/uniform.h"

namespace prtsub {

constexpr const char* kPrtsubVersion = "0.1.0";

struct BakeSettings {
  std::string input;
  LoadOptions load;
  TransferOptions transfer;
  std::string refine = "none";  //!< none, adaptive or uniform
  size_t budget = 0;            //!< adaptive: output triangles
  EdgeEstimate estimate = EdgeEstimate::Probe;
  double max_edge = 0;          //!< adaptive: pre-refine edges longer than this
  size_t batch = 256;           //!< adaptive: faces popped per Embree batch
  UniformOptions uniform;       //!< uniform: levels and scheme
};

struct BakeResult {
  Mesh mesh;             //!< the output mesh
  RowMatrixXd transfer;  //!< #V by N²
  RefineStats refine;
  uint64_t rays = 0;     //!< every transfer ray traced
  double seconds_load = 0, seconds_scene = 0, seconds_transfer = 0, seconds_refine = 0, seconds_total = 0;
  std::vector<std::string> warnings;
  Metadata metadata;     //!< what the asset records
};

//! Runs the pipeline. `progress` (may be empty) is told of transfer points as they finish.
//! \throw InputError, IoError, EmbreeError
BakeResult run_bake(const BakeSettings& settings, const ProgressFn& progress = {});

}  // namespace prtsub
