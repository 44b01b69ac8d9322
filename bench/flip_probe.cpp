// Would edge flips ranked by the transfer lower a simplified asset's error? A probe, not the
// product: the asset's vertices are refitted to dense points of the source (closest-point
// located, a small edge regulariser), then interior edges (the same render vertices on both
// sides: no crease, no seam) are flipped where the two new faces interpolate the points located
// in the old two better, with guards (no face turned more than 60° from the ones it replaces, the
// minimum angle kept at or above min(5°, the old one), the surface moved by at most TOL of the
// diagonal), refitting after each pass. Judged on eval's own reference (2048 rays, 20,000
// points, its fixed seed), which the flips never see.
// usage: bash bench/cpp.sh BUILD flip_probe SOURCE ASSET [PASSES [TOL [TRAIN_POINTS [TRAIN_RAYS]]]]
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <vector>

#include "prtsub/prt/asset.h"
#include "prtsub/prt/closest_point.h"
#include "prtsub/prt/evaluate.h"
#include "prtsub/subdiv/mesh_io.h"

using namespace prtsub;
using V3 = Eigen::Vector3d;

namespace {

// The asset's vertices fitted to the training points on its faces `T` (its positions are
// `mesh`'s: flips change only the faces), each point's location left in `at`.
RowMatrixXd refit(Mesh mesh, const std::vector<Triangle>& T, const Reference& train, double lambda, std::vector<SurfaceLocation>& at) {
  mesh.triangles = T;
  at = closest_points(mesh, train.points, 0, &train.normals);
  const Eigen::Index V = mesh.positions.rows(), K = train.transfer.cols();
  std::vector<Eigen::Triplet<double>> tr;
  RowMatrixXd rhs = RowMatrixXd::Zero(V, K);
  for (size_t i = 0; i < at.size(); ++i) {
    const Triangle& t = T[at[i].face];
    for (int a = 0; a < 3; ++a) {
      rhs.row(t[a]) += at[i].barycentric[a] * train.transfer.row(Eigen::Index(i));
      for (int b = 0; b < 3; ++b) tr.emplace_back(t[a], t[b], at[i].barycentric[a] * at[i].barycentric[b]);
    }
  }
  const double w = lambda * double(at.size()) / double(V);
  for (const Triangle& t : T)
    for (int a = 0; a < 3; ++a) {
      const uint32_t i = t[a], j = t[(a + 1) % 3];
      tr.emplace_back(i, i, w), tr.emplace_back(j, j, w), tr.emplace_back(i, j, -w), tr.emplace_back(j, i, -w);
    }
  for (Eigen::Index v = 0; v < V; ++v) tr.emplace_back(v, v, 1e-9 * w + 1e-12);
  Eigen::SparseMatrix<double> A(V, V);
  A.setFromTriplets(tr.begin(), tr.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
  return ldlt.solve(Eigen::MatrixXd(rhs));
}

double min_angle(const V3& a, const V3& b, const V3& c) {
  auto ang = [](const V3& p, const V3& q, const V3& r) {
    const V3 u = (q - p).normalized(), v = (r - p).normalized();
    return std::acos(std::clamp(u.dot(v), -1.0, 1.0));
  };
  return std::min({ang(a, b, c), ang(b, c, a), ang(c, a, b)});
}

double segment_distance(const V3& p0, const V3& p1, const V3& q0, const V3& q1) {
  double best = 1e300;  // sampled: enough for a guard
  for (int i = 0; i <= 8; ++i) {
    const V3 p = p0 + (p1 - p0) * (i / 8.0);
    const V3 d = q1 - q0;
    const double s = std::clamp((p - q0).dot(d) / std::max(d.squaredNorm(), 1e-300), 0.0, 1.0);
    best = std::min(best, (p - (q0 + s * d)).norm());
  }
  return best;
}

// Squared error of the points in `pts` interpolated on whichever of the faces in `faces` is
// closest (facing the point's normal where one does).
double local_error(const RowMatrixX3d& P, const std::vector<Triangle>& faces, const RowMatrixXd& values,
                   const Reference& ref, const std::vector<size_t>& pts) {
  double e = 0;
  for (size_t i : pts) {
    const V3 p = ref.points.row(Eigen::Index(i)).transpose(), n = ref.normals.row(Eigen::Index(i)).transpose();
    double best = 1e300;
    Eigen::RowVectorXd g;
    for (int pass = 0; pass < 2 && best == 1e300; ++pass)
      for (const Triangle& t : faces) {
        const V3 a = P.row(t[0]), b = P.row(t[1]), c = P.row(t[2]);
        if (pass == 0 && (b - a).cross(c - a).dot(n) <= 0) continue;
        const V3 w = closest_on_triangle(p, a, b, c);
        const double d = (w[0] * a + w[1] * b + w[2] * c - p).norm();
        if (d < best) best = d, g = w[0] * values.row(t[0]) + w[1] * values.row(t[1]) + w[2] * values.row(t[2]);
      }
    e += (g - ref.transfer.row(Eigen::Index(i))).squaredNorm();
  }
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return std::fprintf(stderr, "usage: flip_probe SOURCE ASSET [PASSES [TOL [TRAIN_POINTS [TRAIN_RAYS]]]]\n"), 2;
  const Mesh source = load_mesh(argv[1]);
  const Asset asset = read_asset(argv[2]);
  const int passes = argc > 3 ? std::atoi(argv[3]) : 4;
  const double tol_share = argc > 4 ? std::atof(argv[4]) : 0.005;
  const RayScene scene(source.positions, position_triangles(source));
  ReferenceOptions eo;
  eo.order = asset.order;
  const Reference judge = make_reference(source, scene, eo);
  ReferenceOptions to = eo;
  to.points = argc > 5 ? size_t(std::atoll(argv[5])) : 200000;
  to.rays = argc > 6 ? std::atoi(argv[6]) : 256, to.seed = 777, to.noise_points = 0;
  const Reference train = make_reference(source, scene, to);
  const double diag = (source.positions.colwise().maxCoeff() - source.positions.colwise().minCoeff()).norm();
  const double tol = tol_share * diag, lambda = 1e-3;

  const Mesh base = asset_mesh(asset);
  const RowMatrixX3d& P = asset.positions;
  std::vector<Triangle> T = asset.triangles;
  std::printf("asset as baked: RMS %.3f%%\n", evaluate_by_closest_point(judge, P, T, asset.transfer).rms_percent);
  std::vector<SurfaceLocation> at;
  RowMatrixXd values = refit(base, T, train, lambda, at);
  std::printf("refitted, no flips: RMS %.3f%%\n", evaluate_by_closest_point(judge, P, T, values).rms_percent);
  // Positions welded, so that a flip never adds an edge that exists between other render vertices.
  std::map<std::array<double, 3>, uint32_t> weld;
  std::vector<uint32_t> pos(size_t(P.rows()));
  for (Eigen::Index v = 0; v < P.rows(); ++v) pos[size_t(v)] = weld.try_emplace({P(v, 0), P(v, 1), P(v, 2)}, uint32_t(weld.size())).first->second;
  for (int pass = 0; pass < passes; ++pass) {
    std::vector<std::vector<size_t>> in_face(T.size());
    for (size_t i = 0; i < at.size(); ++i) in_face[at[i].face].push_back(i);
    std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> edges;  // render-vertex edge -> faces
    std::set<std::pair<uint32_t, uint32_t>> welded;
    for (uint32_t f = 0; f < T.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = T[f][k], b = T[f][(k + 1) % 3];
        edges[{std::min(a, b), std::max(a, b)}].push_back(f);
        welded.insert({std::min(pos[a], pos[b]), std::max(pos[a], pos[b])});
      }
    struct Flip { double gain; uint32_t f, g; Triangle n1, n2; };
    std::vector<Flip> flips;
    for (const auto& [e, fs] : edges) {
      if (fs.size() != 2) continue;
      const uint32_t f = fs[0], g = fs[1];
      int kf = 0;
      while (!(T[f][kf] == e.first || T[f][kf] == e.second) || !(T[f][(kf + 1) % 3] == e.first || T[f][(kf + 1) % 3] == e.second)) ++kf;
      const uint32_t a = T[f][kf], b = T[f][(kf + 1) % 3], c = T[f][(kf + 2) % 3];
      uint32_t d = UINT32_MAX;
      for (int k = 0; k < 3; ++k)
        if (T[g][k] != a && T[g][k] != b) d = T[g][k];
      if (d == UINT32_MAX || pos[c] == pos[d] || welded.count({std::min(pos[c], pos[d]), std::max(pos[c], pos[d])})) continue;
      const V3 pa = P.row(a), pb = P.row(b), pc = P.row(c), pd = P.row(d);
      const Triangle n1{a, d, c}, n2{d, b, c};
      const V3 o1 = (pb - pa).cross(pc - pa).normalized(), o2 = (pa - pb).cross(pd - pb).normalized();
      const V3 m1 = (pd - pa).cross(pc - pa).normalized(), m2 = (pb - pd).cross(pc - pd).normalized();
      const double cmin = 0.5;
      if (!(m1.dot(o1) > cmin && m1.dot(o2) > cmin && m2.dot(o1) > cmin && m2.dot(o2) > cmin)) continue;
      const double old_angle = std::min(min_angle(pa, pb, pc), min_angle(pb, pa, pd));
      if (std::min(min_angle(pa, pd, pc), min_angle(pd, pb, pc)) < std::min(5 * M_PI / 180, old_angle)) continue;
      if (segment_distance(pa, pb, pc, pd) > tol) continue;
      std::vector<size_t> pts = in_face[f];
      pts.insert(pts.end(), in_face[g].begin(), in_face[g].end());
      if (pts.empty()) continue;
      const double before = local_error(P, {T[f], T[g]}, values, train, pts), after = local_error(P, {n1, n2}, values, train, pts);
      if (after < 0.98 * before) flips.push_back({before - after, f, g, n1, n2});
    }
    std::sort(flips.begin(), flips.end(), [](const Flip& x, const Flip& y) { return x.gain > y.gain; });
    std::vector<char> touched(T.size(), 0);
    std::set<uint32_t> touched_vertices;
    size_t done = 0;
    for (const Flip& fl : flips) {
      if (touched[fl.f] || touched[fl.g]) continue;
      bool clash = false;  // two flips sharing a vertex may make the same new edge
      for (uint32_t v : {fl.n1[0], fl.n1[1], fl.n1[2], fl.n2[1]}) clash |= touched_vertices.count(v) > 0;
      if (clash) continue;
      for (uint32_t v : {fl.n1[0], fl.n1[1], fl.n1[2], fl.n2[1]}) touched_vertices.insert(v);
      touched[fl.f] = touched[fl.g] = 1;
      T[fl.f] = fl.n1, T[fl.g] = fl.n2;
      ++done;
    }
    values = refit(base, T, train, lambda, at);
    std::printf("pass %d: %zu candidates, %zu flipped; RMS %.3f%%\n", pass + 1, flips.size(), done,
                evaluate_by_closest_point(judge, P, T, values).rms_percent);
    std::fflush(stdout);
    if (done == 0) break;
  }
}
