// How far does an independent, widely used simplifier get on the same mesh? Issue 12, point 4:
// sibenik stops near 45% of its triangles under our guards, and the question is whether that is
// our collapse operator or the mesh. meshoptimizer's meshopt_simplify (Debian's 0.18) is run to
// TARGET triangles with no error limit, two ways:
//   - "welded": on positions alone, so creases and UV seams are invisible to it and only open
//     boundaries constrain it;
//   - "seams": on our render vertices, so a crease or seam (two render vertices at one position)
//     is a seam it may collapse only along, as ours does;
// each with and without meshopt_SimplifyLockBorder. Prints the reached count and meshopt's
// geometric error, as % of the bounding-box diagonal. LIMIT (a fraction of the diagonal, default
// none) caps that error as our surface tolerance caps ours (0.005 by default). With OUT_PREFIX,
// writes each result as OUT_PREFIX<way>_<border>.obj (positions only: whoever loads it computes
// the normals).
// usage: bash bench/cpp.sh BUILD_DIR meshopt_reach MESH TARGET [LIMIT [OUT_PREFIX]]
#include <meshoptimizer.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "prtsub/subdiv/mesh.h"
#include "prtsub/subdiv/mesh_io.h"

using namespace prtsub;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: meshopt_reach MESH TARGET [LIMIT [OUT_PREFIX]]\n");
    return 2;
  }
  const Mesh m = load_mesh(argv[1]);
  const size_t target = std::stoul(argv[2]);
  const double limit = argc > 3 ? std::stod(argv[3]) : 0;
  const std::string prefix = argc > 4 ? argv[4] : "";
  const double diagonal = bounds(m.positions).diagonal();
  std::printf("%s: %zu triangles, target %zu, error limit %s\n", argv[1], m.num_faces(), target,
              limit > 0 ? (std::to_string(100 * limit) + "% of the diagonal").c_str() : "none");
  for (const bool seams : {false, true}) {
    // One vertex per position, or per render vertex (at its position).
    const size_t nv = seams ? m.num_vertices() : size_t(m.positions.rows());
    std::vector<float> pos(3 * nv);
    for (size_t i = 0; i < nv; ++i)
      for (int k = 0; k < 3; ++k) pos[3 * i + k] = float(m.positions(Eigen::Index(seams ? m.vertex_position[i] : i), k));
    std::vector<unsigned> idx;
    for (const Triangle& t : m.triangles)
      for (uint32_t v : t) idx.push_back(seams ? v : m.vertex_position[v]);
    const double scale = meshopt_simplifyScale(pos.data(), nv, 12);
    for (const bool lock : {false, true}) {
      std::vector<unsigned> out(idx.size());
      float err = 0;
      const size_t n = meshopt_simplify(out.data(), idx.data(), idx.size(), pos.data(), nv, 12, 3 * target,
                                        limit > 0 ? float(limit * diagonal / scale) : 1.0f,
                                        lock ? meshopt_SimplifyLockBorder : 0, &err);
      const char* way = seams ? "seams" : "welded";
      const char* border = lock ? "lock_border" : "free_border";
      std::printf("  %-6s %-11s %8zu triangles (%5.1f%% of the input), error %.3f%% of the diagonal\n", way, border, n / 3,
                  100.0 * double(n / 3) / double(m.num_faces()), 100.0 * err * scale / diagonal);
      if (prefix.empty()) continue;
      std::ofstream f(prefix + way + "_" + border + ".obj");
      for (size_t i = 0; i < nv; ++i) f << "v " << pos[3 * i] << ' ' << pos[3 * i + 1] << ' ' << pos[3 * i + 2] << '\n';
      for (size_t i = 0; i < n; i += 3) f << "f " << out[i] + 1 << ' ' << out[i + 1] + 1 << ' ' << out[i + 2] + 1 << '\n';
    }
  }
}
