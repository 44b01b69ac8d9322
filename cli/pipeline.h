// The bake pipeline as one function: mesh -> (uniform refinement) -> transfer at the vertices
// -> (adaptive refinement) -> (samples and fit) -> asset data. `bake` writes its result;
// `compare` and `eval --fits` run it many times.
#pragma once

#include <functional>
#include <string>

#include "prt/asset.h"
#include "prt/fit.h"
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
  EdgeEstimate estimate = EdgeEstimate::Root;
  double max_edge = 0;          //!< adaptive: pre-refine edges longer than this
  size_t batch = 256;           //!< adaptive: faces popped per Embree batch
  UniformOptions uniform;       //!< uniform: levels and scheme
  AssetSignal signal = AssetSignal::Transfer;  //!< ao: order-1 transfer, written as ambient occlusion
  FitOptions fit;               //!< vertex values: point samples, or fitted to surface samples
  SampleOptions samples;        //!< where the fit's samples go
  int sample_rays = 16;         //!< rays per surface sample (many samples with few rays beat the reverse: BENCHMARKS.md)
};

//! Where the fit's samples and their transfer come from, kept so that several fits can share them.
struct FitData {
  SurfaceSamples samples;
  FaceMoments moments;  //!< the samples' transfer, reduced face by face as it is traced
  uint64_t rays = 0;
  double seconds = 0;
};

//! Told when a stage with `total` work items starts, then of items as they finish.
struct BakeProgress {
  std::function<void(const char* stage, size_t total)> stage;
  ProgressFn add;
};

struct BakeResult {
  Mesh mesh;             //!< the output mesh
  RowMatrixXd transfer;  //!< #V by N²
  RefineStats refine;
  RowMatrixXd point;     //!< #V by N²: the point-sampled values (equal to transfer when fit is point)
  FitData fit_data;      //!< the samples (empty when fit is point)
  FitStats fit;
  size_t clamped = 0;    //!< ao: values clamped into [0, 1] after the fit
  uint64_t rays = 0;     //!< every transfer ray traced
  double seconds_load = 0, seconds_scene = 0, seconds_transfer = 0, seconds_refine = 0, seconds_samples = 0,
         seconds_fit = 0, seconds_total = 0;
  std::vector<std::string> warnings;
  Metadata metadata;     //!< what the asset records
};

//! Runs the pipeline. `progress` (either part may be empty) follows the transfer stages.
//! \throw InputError, IoError, EmbreeError, SolverError
BakeResult run_bake(const BakeSettings& settings, const BakeProgress& progress = {});

//! The samples' transfer, reduced to the fit's face moments as it is traced; the same for any
//! thread count.
FaceMoments trace_face_moments(const Mesh& mesh, const RayScene& scene, const SurfaceSamples& samples,
                               const TransferOptions& options, TransferStats* stats = nullptr, const ProgressFn& progress = {});

//! The fit's samples on `mesh` and their transfer (stage "samples").
FitData sample_signal(const Mesh& mesh, const RayScene& scene, const BakeSettings& settings, const BakeProgress& progress = {});

//! ao: clamps order-1 transfer into the AO range [0, 1]·(√π/2); returns how many values moved.
size_t clamp_ao(RowMatrixXd& t0);

}  // namespace prtsub
