// Batches of bakes. Each job loads, keys, bakes and writes on its own: its failure is its
// entry, not the batch's end. The key hashes what determines the asset's bytes: the input's
// bytes, each option a bake reads (listed field by field below; a new option must join the
// list, and the test that changes every option one at a time fails when one is missing), the
// output's format and the library's version. The thread count is left out on purpose: results
// do not depend on it. A job is skipped when its output already records the same key.
#include "prtsub/prt/batch.h"

#include <xxhash.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "prtsub/prt/asset.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"
#include "prtsub/subdiv/stopwatch.h"
#include "prtsub/version.h"

namespace prtsub {
namespace fs = std::filesystem;

const char* batch_status_name(BatchStatus s) {
  return s == BatchStatus::Baked ? "baked" : s == BatchStatus::Skipped ? "skipped" : "failed";
}

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool is_mesh(const fs::path& p) {
  const std::string e = lower(p.extension().string());
  return e == ".obj" || e == ".ply" || e == ".off" || e == ".stl";
}

// Every option bake() reads, as text, in a fixed order.
std::string options_text(const BatchOptions& b, const std::string& output) {
  const BakeOptions o = resolve_bake_options(b.bake);
  std::ostringstream s;
  s.precision(17);
  s << "version " << kVersion << "\nformat " << lower(fs::path(output).extension().string()) << "\n";
  s << "order " << o.transfer.order << " rays " << o.transfer.rays << " seed " << o.transfer.seed << "\n";
  s << "estimator " << estimator_name(o.transfer.estimator) << " " << o.transfer.progressive.acceleration << " "
    << o.transfer.progressive.gauss_seidel << " " << int(o.transfer.progressive.denominator) << "\n";
  s << "order_auto " << o.order_auto << " " << o.order_choice.max_order << " " << o.order_choice.tolerance_percent << " "
    << o.order_choice.pilot_points;
  for (double p : o.order_choice.band_power) s << " " << p;
  s << "\n";
  s << "signal " << asset_signal_name(o.signal) << " refine " << refinement_name(o.refine) << "\n";
  s << "adaptive " << o.adaptive.budget << " " << o.adaptive.batch << " " << o.adaptive.max_edge << " " << estimate_name(o.estimate) << "\n";
  s << "uniform " << o.uniform.levels << " " << uniform_scheme_name(o.uniform.scheme) << "\n";
  const FitOptions& f = o.fit;
  s << "fit " << fit_method_name(f.method) << " " << regularizer_name(f.regularizer) << " " << f.alpha << " " << mass_matrix_name(f.mass)
    << " " << f.control_variate << " " << fit_solver_name(f.solver) << " " << f.cg_tolerance << " " << f.cg_max_iterations << " " << f.stiff_mass << " "
    << f.weigh_by_noise << " " << non_negative_name(f.non_negative) << "\n";
  s << "samples " << o.samples.per_triangle << " " << o.samples.density << " " << o.samples.min_per_triangle << " " << o.samples.seed << "\n";
  s << "allocation " << sample_allocation_name(o.allocation) << " vertex_share " << o.vertex_share << " target " << o.target_error
    << " rays_auto " << o.rays_auto << " sample_rays " << o.sample_rays << " sample_rays_auto " << o.sample_rays_auto << " unshadowed " << o.unshadowed_projection << " alpha_auto " << o.alpha_auto;
  for (double a : o.alpha_choices) s << " " << a;
  s << "\n";
  const PilotOptions& p = o.pilot;
  s << "pilot " << p.per_triangle << " " << p.min_samples << " " << p.rays << " " << p.rings << " " << p.significance << " " << p.area_share
    << " " << p.holdout << " " << p.first_share << " " << p.first_significance << " screen " << p.screen_ratio << " " << p.screen_samples << "\n";
  const SimplifyOptions& q = o.simplify;
  s << "simplify " << simplify_metric_name(q.metric) << " " << q.geometry_weight << " " << q.min_angle_deg << " " << q.feature_tolerance << " "
    << q.surface_tolerance << " " << q.max_surface_tolerance << " " << o.simplified_alpha << " auto " << o.auto_share << " " << o.auto_cycles << " " << o.auto_cycle_share << "\n";
  s << "stage " << (o.refine_only ? "refine" : "all") << "\n";
  s << "basis " << (o.sg_lobes > 0 ? "sg " + std::to_string(o.sg_lobes) + (o.sg_signed ? " signed" : " non-negative") : std::string("sh")) << "\n";
  s << "bounce " << o.bounce.bounces << " " << o.bounce.until_converged << " " << o.bounce.albedo << " " << o.bounce.fit_samples << " rekey " << o.rekey_share << "\n";
  if (o.albedo_colour.coloured()) {  // a map is named and its bytes hashed: an edited texture bakes again
    s << "albedo " << albedo_description(o.albedo_colour);
    const std::string map_bytes = o.albedo_colour.source == AlbedoSource::Map ? read_file_bytes(o.albedo_colour.map) : std::string();
    if (o.albedo_colour.source == AlbedoSource::Map) s << " " << XXH3_64bits(map_bytes.data(), map_bytes.size());
    s << "\n";
  }
  s << "crease " << b.load.crease_angle_deg << "\n";
  s << "gltf " << (b.gltf.up == UpAxis::Z ? "z" : "y") << " " << b.gltf.quantize << " " << b.gltf.compress << "\n";
  return s.str();
}

}  // namespace

std::vector<BatchJob> batch_jobs(const std::vector<std::string>& inputs, const std::string& out_dir, const std::string& extension) {
  const std::string ext = lower(extension);
  if (ext != ".ply" && ext != ".glb" && ext != ".gltf") throw InputError("batch: unknown asset format '" + extension + "' (.ply, .glb, .gltf)");
  std::vector<BatchJob> jobs;
  auto add = [&](const fs::path& input, const fs::path& relative) {
    fs::path out = fs::path(out_dir) / relative;
    out.replace_extension(ext);
    jobs.push_back({input.string(), out.string()});
  };
  std::function<void(const std::string&, const fs::path&)> expand = [&](const std::string& item, const fs::path& base) {
    if (!item.empty() && item[0] == '@') {
      const fs::path list = fs::path(item.substr(1));
      std::istringstream lines(read_file_bytes(list.string()));
      std::string line;
      while (std::getline(lines, line)) {
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
        const size_t first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        const fs::path p = fs::path(line.substr(first));
        expand((p.is_absolute() ? p : list.parent_path() / p).string(), {});
      }
      return;
    }
    const fs::path p(item);
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      std::vector<fs::path> found;
      for (fs::recursive_directory_iterator it(p, ec), end; !ec && it != end; it.increment(ec))
        if (it->is_regular_file(ec) && is_mesh(it->path())) found.push_back(it->path());
      if (ec) throw IoError(item + ": cannot list the folder (" + ec.message() + ")");
      std::sort(found.begin(), found.end());
      for (const fs::path& f : found) add(f, fs::relative(f, p));
    } else if (fs::is_regular_file(p, ec)) {
      add(p, p.filename());
    } else {
      throw IoError(item + ": no such file or folder");
    }
    (void)base;
  };
  for (const std::string& item : inputs) expand(item, {});
  std::map<std::string, std::string> seen;
  for (const BatchJob& j : jobs) {
    auto [it, fresh] = seen.emplace(fs::path(j.output).lexically_normal().string(), j.input);
    if (!fresh) throw InputError("batch: " + it->second + " and " + j.input + " would both write " + j.output);
  }
  return jobs;
}

std::string bake_key(const std::string& input_bytes, const BatchOptions& options, const std::string& output) {
  XXH3_state_t* state = XXH3_createState();
  if (!state) throw Error("batch: cannot allocate a hash state");
  XXH3_128bits_reset(state);
  const std::string text = options_text(options, output);
  const uint64_t size = input_bytes.size();
  XXH3_128bits_update(state, &size, sizeof size);
  XXH3_128bits_update(state, input_bytes.data(), input_bytes.size());
  XXH3_128bits_update(state, text.data(), text.size());
  const XXH128_hash_t h = XXH3_128bits_digest(state);
  XXH3_freeState(state);
  char hex[33];
  std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h.high64), static_cast<unsigned long long>(h.low64));
  return hex;
}

std::string asset_bake_key(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return "";
  try {
    for (const auto& [key, value] : read_asset(path).metadata)
      if (key == "bake_key") return value;
  } catch (const Error&) {
  }
  return "";
}

std::vector<BatchEntry> bake_batch(const std::vector<BatchJob>& jobs, const BatchOptions& options, const BatchProgress& progress) {
  std::vector<BatchEntry> entries;
  entries.reserve(jobs.size());
  for (size_t i = 0; i < jobs.size(); ++i) {
    const BatchJob& job = jobs[i];
    if (progress.start) progress.start(i, jobs.size(), job);
    BatchEntry e;
    e.job = job;
    Stopwatch clock;
    BakeResult result;
    bool baked = false;
    try {
      const std::string bytes = read_file_bytes(job.input);
      e.key = bake_key(bytes, options, job.output);
      if (!options.force && asset_bake_key(job.output) == e.key) {
        e.status = BatchStatus::Skipped;
      } else {
        const Mesh mesh = parse_mesh(bytes, job.input, options.load);
        e.triangles_in = mesh.num_faces();
        BakeOptions o = options.bake;
        o.source = job.input;
        result = bake(mesh, o, progress.bake);
        result.metadata.push_back({"bake_key", e.key});
        const fs::path parent = fs::path(job.output).parent_path();
        std::error_code ec;
        if (!parent.empty()) fs::create_directories(parent, ec);
        if (ec) throw IoError(job.output + ": cannot create its folder (" + ec.message() + ")");
        if (is_gltf_path(job.output)) write_gltf_asset(job.output, result.mesh, result.transfer, result.metadata, o.signal, options.gltf, result.albedo);
        else write_asset(job.output, result.mesh, result.transfer, result.metadata, o.signal, result.albedo);
        e.status = BatchStatus::Baked;
        e.triangles_out = result.mesh.num_faces();
        e.vertices_out = result.mesh.num_vertices();
        e.rays = result.rays;
        baked = true;
      }
    } catch (const Error& x) {  // bad input, IO, Embree, the solver: this job's failure, named by its file
      const std::string what = x.what();
      e.error = what.rfind(job.input, 0) == 0 || what.rfind(job.output, 0) == 0 ? what : job.input + ": " + what;
    }
    e.seconds = clock.total();
    entries.push_back(e);
    if (progress.done) progress.done(i, jobs.size(), entries.back(), baked ? &result : nullptr);
  }
  return entries;
}

}  // namespace prtsub
