// Bakes a mesh that never was a file: a square column standing on a floor, built in
// memory, refined adaptively to 2,000 triangles where its shadow falls, fitted, and written as a
// PRT asset. Everything here is the installed library's public API.
//
//   bake_in_memory OUT.ply
#include <cstdio>
#include <exception>

#include <prtsub/prt/asset.h>
#include <prtsub/prt/bake.h>
#include <prtsub/subdiv/mesh_io.h>
#include <prtsub/version.h>

namespace {

// A square floor (two triangles) and a box standing on it: a RawMesh is what a file would say.
prtsub::RawMesh column_on_floor() {
  prtsub::RawMesh raw;
  raw.positions.resize(12, 3);
  raw.positions << -2, 0, -2, 2, 0, -2, 2, 0, 2, -2, 0, 2,                                      // floor
      -0.3, 0, -0.3, 0.3, 0, -0.3, 0.3, 0, 0.3, -0.3, 0, 0.3,                                    // box bottom
      -0.3, 1.5, -0.3, 0.3, 1.5, -0.3, 0.3, 1.5, 0.3, -0.3, 1.5, 0.3;                            // box top
  const int faces[][3] = {{0, 2, 1}, {0, 3, 2},                                                  // floor, facing +y
                          {8, 10, 9}, {8, 11, 10},                                               // top
                          {4, 9, 5}, {4, 8, 9}, {5, 10, 6}, {5, 9, 10},                          // sides, outward
                          {6, 11, 7}, {6, 10, 11}, {7, 8, 4}, {7, 11, 8}};
  raw.face_offsets.push_back(0);
  for (const auto& f : faces) {
    for (int v : f) raw.face_indices.push_back(v);
    raw.face_offsets.push_back(raw.face_indices.size());
  }
  return raw;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: bake_in_memory OUT.ply\n");
    return 2;
  }
  try {
    const prtsub::Mesh mesh = prtsub::build_mesh(column_on_floor(), "column on floor");

    prtsub::BakeOptions options;
    options.refine = prtsub::Refinement::Adaptive;
    options.adaptive.budget = 2000;
    options.transfer.rays = 64;
    options.source = "examples/bake_in_memory";
    prtsub::BakeProgress progress;
    progress.stage = [](const char* stage, size_t total) { std::printf("  %s: %zu items\n", stage, total); };

    const prtsub::BakeResult result = prtsub::bake(mesh, options, progress);
    prtsub::write_asset(argv[1], result.mesh, result.transfer, result.metadata);

    std::printf("prtsub %s: %zu -> %zu triangles, %llu rays in %.2f s, fit by %s; wrote %s\n", prtsub::kVersion,
                mesh.num_faces(), result.mesh.num_faces(), static_cast<unsigned long long>(result.rays),
                result.seconds_total, result.fit.solver.c_str(), argv[1]);
    for (const std::string& w : result.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bake_in_memory: %s\n", e.what());
    return 1;
  }
}
