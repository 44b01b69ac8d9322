// How well each vertex's own variance estimate (the two lattice halves of shadowed_transfer)
// predicts its real squared error, and what planning the second round of vertex rays on it, or
// on it averaged over rings of faces (smoothed_variance), could gain. One scene's AO (order 1),
// or its transfer of order ORDER (errors summed over the values): R rays at seed 0 against a
// reference of REF rays at seed 7 (whose own noise, estimated the same way, is subtracted from
// the mean).
// The plans are modelled, not traced: every vertex keeps its R rays and a budget of R more per
// vertex is water-filled on √(w·planner) (plan_top_up's rule without the powers of two); a
// vertex's squared error then falls as R/R_i. "known error" plans on the real squared errors
// averaged over six rings (what a planner that knew each vertex's variance would use), "even"
// gives every vertex R more.
// usage: bash bench/variance_calibration.sh BUILD SCENE [R] [REF] [ORDER]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/transfer.h"
#include "prtsub/prt/vertex_top_up.h"
#include "prtsub/subdiv/mesh_io.h"

using namespace prtsub;

namespace {

double weighted_mean(const std::vector<double>& x, const std::vector<double>& w) {
  double s = 0, a = 0;
  for (size_t i = 0; i < x.size(); ++i) s += w[i] * x[i], a += w[i];
  return s / a;
}

// Extra rays R_i − R per vertex for a mean of `budget` more, R_i = max(R, λ√(w p)).
std::vector<double> water_fill(const std::vector<double>& p, const std::vector<double>& w, double R, double budget) {
  const size_t V = p.size();
  auto spent = [&](double lambda) {
    double s = 0;
    for (size_t i = 0; i < V; ++i) s += std::max(0.0, lambda * std::sqrt(w[i] * p[i]) - R);
    return s / double(V);
  };
  double lo = 0, hi = 1;
  while (spent(hi) < budget) hi *= 2;
  for (int k = 0; k < 200; ++k) (spent(0.5 * (lo + hi)) < budget ? lo : hi) = 0.5 * (lo + hi);
  std::vector<double> rays(V);
  for (size_t i = 0; i < V; ++i) rays[i] = std::max(R, hi * std::sqrt(w[i] * p[i]));
  return rays;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return std::fprintf(stderr, "usage: variance_calibration SCENE [R] [REF] [ORDER]\n"), 2;
  const int R = argc > 2 ? std::atoi(argv[2]) : 256, ref_rays = argc > 3 ? std::atoi(argv[3]) : 4096, order = argc > 4 ? std::atoi(argv[4]) : 1;
  const Mesh mesh = load_mesh(argv[1]);
  const RayScene scene(mesh.positions, position_triangles(mesh));
  const RowMatrixX3d offsets = vertex_offset_directions(mesh), points = vertex_positions(mesh);
  TransferOptions o;
  o.order = order, o.rays = R, o.seed = 0;
  std::vector<double> var, ref_var;
  const RowMatrixXd t = shadowed_transfer(scene, points, mesh.normals, o, nullptr, {}, &offsets, &var);
  o.rays = ref_rays, o.seed = 7;
  const RowMatrixXd ref = shadowed_transfer(scene, points, mesh.normals, o, nullptr, {}, &offsets, &ref_var);
  const size_t V = mesh.num_vertices();
  const std::vector<double> w = vertex_areas(mesh), rays(V, R);
  std::vector<double> err2(V), own(V);
  for (size_t i = 0; i < V; ++i) err2[i] = (t.row(i) - ref.row(i)).squaredNorm(), own[i] = std::isfinite(var[i]) ? var[i] : 0;
  std::printf("%s: %zu vertices, order %d, %d rays against %d\n", argv[1], V, order, R, ref_rays);
  std::printf("area-weighted mean: own variance %.3g, squared error %.3g (reference's own variance %.3g subtracted)\n",
              weighted_mean(own, w), weighted_mean(err2, w) - weighted_mean(ref_var, w), weighted_mean(ref_var, w));
  const std::vector<double> ring1 = smoothed_variance(mesh, own, rays, 1), ring6 = smoothed_variance(mesh, own, rays, 6);
  // Vertices by their own estimate: those reading 0, then tenths of the rest.
  std::printf("\n| own estimate | vertices | mean own | mean squared error | one ring | six rings |\n|---|---:|---:|---:|---:|---:|\n");
  std::vector<size_t> by_own(V);
  for (size_t i = 0; i < V; ++i) by_own[i] = i;
  std::sort(by_own.begin(), by_own.end(), [&](size_t a, size_t b) { return own[a] < own[b]; });
  // Halves that agree leave round-off (1e-32 where the mean is 1e-5): that counts as 0.
  const double zero = 1e-12 * weighted_mean(own, w);
  const size_t zeros = static_cast<size_t>(std::count_if(own.begin(), own.end(), [&](double v) { return v <= zero; }));
  auto row = [&](const char* name, size_t b, size_t e) {
    double s[4] = {0, 0, 0, 0};
    for (size_t k = b; k < e; ++k) s[0] += own[by_own[k]], s[1] += err2[by_own[k]], s[2] += ring1[by_own[k]], s[3] += ring6[by_own[k]];
    const double n = double(std::max<size_t>(e - b, 1));
    std::printf("| %s | %zu | %.3g | %.3g | %.3g | %.3g |\n", name, e - b, s[0] / n, s[1] / n, s[2] / n, s[3] / n);
  };
  row("0", 0, zeros);
  for (int d = 0; d < 10; ++d) {
    const std::string name = "tenth " + std::to_string(d + 1) + " of the rest";
    row(name.c_str(), zeros + (V - zeros) * d / 10, zeros + (V - zeros) * (d + 1) / 10);
  }
  // Modelled second rounds: the squared error left, against an even one.
  const std::vector<double> known = smoothed_variance(mesh, err2, rays, 6);
  std::vector<double> even(V, 1.0);
  std::printf("\n| plan of R more rays per vertex, on | modelled squared error | against even |\n|---|---:|---:|\n");
  double even_error = 0;
  for (const auto& [name, p] : std::vector<std::pair<const char*, const std::vector<double>*>>{
           {"even", &even}, {"own estimate", &own}, {"one ring", &ring1}, {"six rings", &ring6}, {"known error", &known}}) {
    const std::vector<double> Ri = p == &even ? std::vector<double>(V, 2.0 * R) : water_fill(*p, w, R, R);
    std::vector<double> left(V);
    for (size_t i = 0; i < V; ++i) left[i] = err2[i] * R / Ri[i];
    const double e = weighted_mean(left, w);
    if (p == &even) even_error = e;
    std::printf("| %s | %.4g | %.3f |\n", name, e, e / even_error);
  }
  return 0;
}
