// Where does asset B lose to asset A? Both are judged as `eval --locate closest` judges them: one
// reference on the source (eval's defaults but RAYS rays a point), each point located at its
// closest facing point of each asset (evaluate_by_closest_point, asked for each point's error).
// Prints both RMS, as eval does, and the source faces that gain most squared error from A to B,
// each with its share of the total gain, its point count, its centre and its normal: a loss
// spread over the surface, or one feature broken. Then, for each asset, the squared error by the
// point's distance to the asset's surface (in shares of the source's bounding-box diagonal):
// error far from the asset is the shape's, error close to it the values' interpolation.
// usage: bash bench/cpp.sh BUILD eval_diff SOURCE A B [RAYS] [FACES]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <vector>

#include "prtsub/prt/asset.h"
#include "prtsub/prt/closest_point.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/subdiv/mesh_io.h"

using namespace prtsub;

namespace {

// Each reference point's squared error in the asset, in units of ‖t_unshadowed‖².
std::vector<double> squared_errors(const Reference& ref, const Asset& a) {
  std::vector<double> e;
  evaluate_by_closest_point(ref, a.positions, a.triangles, a.transfer, 0, &e);
  for (double& x : e) x *= x;
  return e;
}

void by_distance(const char* name, const Reference& ref, const Asset& a, const std::vector<double>& e, double diag) {
  const std::vector<SurfaceLocation> at = closest_points(asset_mesh(a), ref.points, 0, &ref.normals);  // as eval locates
  const double edges[] = {0.0025, 0.005, 0.01, 0.02, 0.04, INFINITY};
  double sum[6] = {}, total = 0;
  int n[6] = {};
  for (size_t i = 0; i < e.size(); ++i) {
    int b = 0;
    while (at[i].distance > edges[b] * diag) ++b;
    sum[b] += e[i], ++n[b], total += e[i];
  }
  std::printf("\n%s by distance to its surface:\n| distance, share of the diagonal | points | share of squared error | RMS %% |\n|---|---:|---:|---:|\n", name);
  for (int b = 0; b < 6; ++b)
    if (n[b] > 0) std::printf("| %s%g | %d | %.3f | %.2f |\n", b < 5 ? "≤ " : "> ", b < 5 ? edges[b] : edges[4], n[b], sum[b] / total, 100 * std::sqrt(sum[b] / n[b]));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) return std::fprintf(stderr, "usage: eval_diff SOURCE A B [RAYS] [FACES]\n"), 2;
  const Mesh source = load_mesh(argv[1]);
  const Asset A = read_asset(argv[2]), B = read_asset(argv[3]);
  const RayScene scene(source.positions, position_triangles(source));
  ReferenceOptions ro;
  ro.rays = argc > 4 ? std::atoi(argv[4]) : 1024;
  ro.order = A.order;
  const int faces = argc > 5 ? std::atoi(argv[5]) : 15;
  const Reference ref = make_reference(source, scene, ro);
  const std::vector<double> ea = squared_errors(ref, A), eb = squared_errors(ref, B);
  const double unit = double(ea.size());
  double sa = 0, sb = 0;
  for (size_t k = 0; k < ea.size(); ++k) sa += ea[k], sb += eb[k];
  std::printf("%zu points, %d rays: RMS A %.3f%%, B %.3f%%\n", ea.size(), ro.rays, 100 * std::sqrt(sa / unit),
              100 * std::sqrt(sb / unit));
  std::map<uint32_t, std::pair<double, int>> by_face;
  for (size_t k = 0; k < ea.size(); ++k) {
    auto& [gain, n] = by_face[ref.source_face[k]];
    gain += eb[k] - ea[k], ++n;
  }
  std::vector<std::pair<double, uint32_t>> order;
  for (const auto& [f, g] : by_face) order.push_back({g.first, f});
  std::sort(order.rbegin(), order.rend());
  const double total = sb - sa;
  double so_far = 0;
  std::printf("| source face | points | share of B's gain | so far | centre | normal |\n|---:|---:|---:|---:|---|---|\n");
  for (int i = 0; i < faces && i < int(order.size()); ++i) {
    so_far += order[size_t(i)].first;
    const Triangle& t = source.triangles[order[size_t(i)].second];
    const Eigen::Vector3d a = source.point(t[0]), b = source.point(t[1]), c = source.point(t[2]);
    const Eigen::Vector3d centre = (a + b + c) / 3, n = (b - a).cross(c - a).normalized();
    std::printf("| %u | %d | %.3f | %.3f | %.1f %.1f %.1f | %.2f %.2f %.2f |\n", order[size_t(i)].second, by_face[order[size_t(i)].second].second,
                order[size_t(i)].first / total, so_far / total, centre.x(), centre.y(), centre.z(), n.x(), n.y(), n.z());
  }
  const double diag = (source.positions.colwise().maxCoeff() - source.positions.colwise().minCoeff()).norm();
  by_distance("A", ref, A, ea, diag);
  by_distance("B", ref, B, eb, diag);
}
