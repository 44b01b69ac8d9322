// The unshadowed transfer's curvature, projected exactly (docs/fit.md, "The unshadowed part").
//
// Shadowed transfer is t(p) = ∫ V·max(n(p)·ω, 0)·y(ω) dω: the clamped cosine turned to the normal
// (unshadowed, t_u,lm = Â_l·y_lm(n), known in closed form), less what the scene blocks. The asset
// interpolates vertex values linearly, and t_u is not linear in p: n(p) is the normalised
// interpolation of the corner normals, and y_lm is curved in n. On a dense scan that curvature,
// not noise, is most of what point sampling leaves at high ray counts (armadillo: 0.95% of ‖t_u‖ at
// 4096 rays per vertex; t_u's curvature alone, 0.98%). Samples see it only through their noise.
// Here it is integrated instead. Where a point is partly enclosed the curvature shows in t only as
// far as the point is open (an enclosed region's t is near zero and near linear), so the known
// part is w(p)·t_u(n(p)), w the vertices' open shares (DC against an open point's), interpolated.
//
// x = M⁻¹c with M the P1 mass matrix over every face of positive area (∫h_i h_j: area/6 on the
// diagonal, area/12 off it) and c_i = ∫ h_i w t_u(n(p)) dA, each face's integrals by Dunavant's
// degree-5 rule on 4^L subtriangles, L from the spread of its corner normals (t_u(n(p)) is smooth
// but not polynomial; where normals turn far across a face, as on a coarse smooth mesh, one rule
// per face would not do). M scaled to a unit diagonal has its eigenvalues in [1/2, 2] on any mesh,
// so conjugate gradients converge in about fifteen passes whatever its size: linear in the
// vertices. Each face is integrated once (kept in float: far below any bake's noise), and each row
// is gathered from its vertex's corners in one fixed order, so the result does not depend on the
// thread count. Bands with Â_l = 0 (odd l > 1) are identically zero and are not solved.
#include "prtsub/prt/unshadowed_projection.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "prtsub/prt/block_cg.h"
#include "prtsub/prt/parallel.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/adjacency.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

// Dunavant's 7-point rule, exact for polynomials of degree 5 on a triangle.
struct QuadraturePoint {
  double b[3];
  double w;
};
constexpr double kA = 0.059715871789770, kB = 0.470142064105115, kC = 0.797426985353087,
                 kD = 0.101286507323456;
constexpr double kW0 = 0.225, kW1 = 0.132394152788506, kW2 = 0.125939180544827;
constexpr std::array<QuadraturePoint, 7> kRule{{{{1 / 3.0, 1 / 3.0, 1 / 3.0}, kW0},
                                                {{kA, kB, kB}, kW1},
                                                {{kB, kA, kB}, kW1},
                                                {{kB, kB, kA}, kW1},
                                                {{kC, kD, kD}, kW2},
                                                {{kD, kC, kD}, kW2},
                                                {{kD, kD, kC}, kW2}}};

// Subdivision levels for a face whose corner normals span `cos_spread` (the least pairwise cosine):
// 4^L subtriangles, so that each spans about 20° of normal or less.
int levels_for(double cos_spread) {
  if (cos_spread > 0.94) return 0;  // within 20°
  if (cos_spread > 0.77) return 1;  // 40°
  if (cos_spread > 0.17) return 2;  // 80°
  return 3;
}

// The bands whose clamped-cosine coefficient is not zero: the columns worth solving.
std::vector<int> live_columns(int order) {
  std::vector<int> cols;
  for (int l = 0; l < order; ++l)
    if (std::abs(clamped_cosine_band(l)) > 1e-12)
      for (int m = -l; m <= l; ++m) cols.push_back(sh_index(l, m));
  return cols;
}

// ∫ h_c t_u(n(p)) over face f for its three corners c, into out (3 rows of the live columns).
// Returns the points used.
size_t face_integrals(const Mesh& mesh, size_t f, int order, const std::vector<int>& cols,
                      double area, const std::vector<double>* weight, double* sh, double* out) {
  const Triangle& t = mesh.triangles[f];
  const double w0 = weight ? (*weight)[t[0]] : 1, w1 = weight ? (*weight)[t[1]] : 1,
               w2 = weight ? (*weight)[t[2]] : 1;
  const Eigen::Vector3d n0 = mesh.normals.row(t[0]), n1 = mesh.normals.row(t[1]),
                        n2 = mesh.normals.row(t[2]);
  const Eigen::Vector3d p0 = mesh.point(t[0]);
  Eigen::Vector3d fn = (mesh.point(t[1]) - p0).cross(mesh.point(t[2]) - p0);
  fn = fn.norm() > 0 ? Eigen::Vector3d(fn.normalized()) : Eigen::Vector3d::UnitZ();
  const int L = levels_for(std::min({n0.dot(n1), n0.dot(n2), n1.dot(n2)}));
  const int s = 1 << L;  // subdivisions per edge: s² subtriangles, upright and inverted
  const double sub_area = area / double(s * s);
  const size_t K = cols.size();
  std::fill(out, out + 3 * K, 0.0);
  size_t points = 0;
  for (int i = 0; i < s; ++i)
    for (int j = 0; j < s - i; ++j)
      for (int inverted = 0; inverted < (j < s - i - 1 ? 2 : 1); ++inverted) {
        // corners of the subtriangle in the face's (u, v) coordinates (barycentrics 1 − u − v, u,
        // v)
        const double u[3] = {inverted ? double(i + 1) : double(i),
                             inverted ? double(i) : double(i + 1),
                             inverted ? double(i + 1) : double(i)};
        const double v[3] = {double(j), double(j + (inverted ? 1 : 0)), double(j + 1)};
        for (const QuadraturePoint& q : kRule) {
          const double pu = (q.b[0] * u[0] + q.b[1] * u[1] + q.b[2] * u[2]) / s;
          const double pv = (q.b[0] * v[0] + q.b[1] * v[1] + q.b[2] * v[2]) / s;
          const double bary[3] = {1 - pu - pv, pu, pv};
          Eigen::Vector3d n = bary[0] * n0 + bary[1] * n1 + bary[2] * n2;
          n = n.norm() > 1e-12 ? Eigen::Vector3d(n.normalized()) : fn;
          unshadowed_transfer(order, n, sh);
          const double open = bary[0] * w0 + bary[1] * w1 + bary[2] * w2;
          for (int c = 0; c < 3; ++c) {
            const double w = q.w * sub_area * bary[c] * open;
            for (size_t k = 0; k < K; ++k) out[size_t(c) * K + k] += w * sh[cols[k]];
          }
          ++points;
        }
      }
  return points;
}

}  // namespace

RowMatrixXd unshadowed_at(const RowMatrixX3d& normals, int order) {
  if (order < 1 || order > 10)
    throw InputError("unshadowed transfer: the order must be between 1 and 10");
  RowMatrixXd t(normals.rows(), sh_count(order));
  for (Eigen::Index i = 0; i < normals.rows(); ++i)
    unshadowed_transfer(order, normals.row(i).transpose(), t.row(i).data());
  return t;
}

std::vector<double> open_share(const RowMatrixXd& values) {
  std::vector<double> w(static_cast<size_t>(values.rows()), 0.0);
  if (values.cols() == 0) return w;
  const double open =
      clamped_cosine_band(0) * sh_eval(1, Eigen::Vector3d::UnitZ())[0];  // t_u,0 for any normal
  for (Eigen::Index i = 0; i < values.rows(); ++i) {
    const double r = values(i, 0) / open;
    w[static_cast<size_t>(i)] = std::isfinite(r) ? std::clamp(r, 0.0, 1.0) : 0.0;
  }
  return w;
}

RowMatrixXd unshadowed_projection(const Mesh& mesh, int order, const UnshadowedProjectionOptions& o,
                                  UnshadowedProjectionStats* stats,
                                  const std::vector<double>* weight) {
  const Stopwatch clock;
  const size_t V = mesh.num_vertices(), F = mesh.num_faces();
  if (static_cast<size_t>(mesh.normals.rows()) != V)
    throw InputError("unshadowed projection: the mesh needs one normal per vertex");
  if (weight && weight->size() != V)
    throw InputError("unshadowed projection: one weight per vertex expected");
  RowMatrixXd x = unshadowed_at(mesh.normals, order);
  if (weight)
    for (size_t i = 0; i < V; ++i) x.row(static_cast<Eigen::Index>(i)) *= (*weight)[i];
  const std::vector<int> cols = live_columns(order);
  const auto K = static_cast<Eigen::Index>(cols.size());
  std::vector<double> area(F, 0.0);
  for (size_t f = 0; f < F; ++f) {
    const Triangle& t = mesh.triangles[f];
    const double a = triangle_area(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]));
    area[f] = std::isfinite(a) && a > 0 ? a : 0;
  }
  const Buckets corners = vertex_corners(mesh.triangles, V);
  // The unknowns: vertices with a face of positive area (the rest keep w_i·t_u(n_i)), numbered
  // breadth-first so that each row's neighbours, and the faces they share, are near in memory.
  std::vector<Eigen::Index> slot(V, -1);
  std::vector<uint32_t> vertex_of;  // by unknown
  vertex_of.reserve(V);
  for (uint32_t i : breadth_first_order(mesh.triangles, corners, V)) {
    bool any = false;
    for (uint32_t e = corners.begin[i]; e < corners.begin[i + 1] && !any; ++e) any = area[corners.entry[e] / 3] > 0;
    if (any) slot[i] = static_cast<Eigen::Index>(vertex_of.size()), vertex_of.push_back(i);
  }
  const auto n = static_cast<Eigen::Index>(vertex_of.size());
  UnshadowedProjectionStats st;
  st.fixed_vertices = V - static_cast<size_t>(n);
  if (n == 0 || K == 0) {
    st.seconds = clock.total();
    if (stats) *stats = st;
    return x;
  }
  // Each face's integrals once (in float: the right-hand side needs no more than the samples'
  // noise allows, and a dense mesh has many faces), then each row gathered from its vertex's
  // corners in their fixed order: the mass entries (neighbours sorted, merged) and the sums.
  const auto Ku = static_cast<size_t>(K);
  std::vector<float> integrals(3 * Ku * F, 0.0f);
  std::vector<size_t> points_per_face(F, 0);
  parallel_range<size_t>(F, o.threads, 512, [&](const tbb::blocked_range<size_t>& range) {
    std::vector<double> sh(static_cast<size_t>(sh_count(order))), face(3 * Ku);
    for (size_t f = range.begin(); f != range.end(); ++f) {
      if (!(area[f] > 0)) continue;
      points_per_face[f] =
          face_integrals(mesh, f, order, cols, area[f], weight, sh.data(), face.data());
      for (size_t k = 0; k < 3 * Ku; ++k) integrals[3 * Ku * f + k] = static_cast<float>(face[k]);
    }
  });
  // Row i's mass entries: (neighbour's unknown, ∫h_i h_j) sorted and merged, into buf.
  auto gather_row = [&](size_t i, std::vector<std::pair<Eigen::Index, double>>& buf) {
    buf.clear();
    for (uint32_t e = corners.begin[i]; e < corners.begin[i + 1]; ++e) {
      const size_t f = corners.entry[e] / 3;
      const uint32_t c = corners.entry[e] % 3;
      if (!(area[f] > 0)) continue;
      for (uint32_t k = 0; k < 3; ++k)
        buf.emplace_back(slot[mesh.triangles[f][k]], area[f] * (k == c ? 2.0 : 1.0) / 12.0);
    }
    std::sort(buf.begin(), buf.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    size_t w = 0;
    for (size_t r = 0; r < buf.size(); ++r) {
      if (w > 0 && buf[w - 1].first == buf[r].first)
        buf[w - 1].second += buf[r].second;
      else
        buf[w++] = buf[r];
    }
    buf.resize(w);
  };
  // Pass 1: row sizes, diagonals and right-hand sides (each row's corners in their fixed order).
  std::vector<Eigen::Index> row_size(static_cast<size_t>(n) + 1, 0);
  Eigen::VectorXd scale(n);
  RowMatrixXd rhs = RowMatrixXd::Zero(n, K);
  parallel_range<Eigen::Index>(n, o.threads, 1024, [&](const tbb::blocked_range<Eigen::Index>& range) {
    std::vector<std::pair<Eigen::Index, double>> buf;
    for (Eigen::Index r = range.begin(); r != range.end(); ++r) {
      const uint32_t i = vertex_of[static_cast<size_t>(r)];
      gather_row(i, buf);
      row_size[static_cast<size_t>(r) + 1] = static_cast<Eigen::Index>(buf.size());
      for (const auto& [j, v] : buf)
        if (j == r) scale[r] = 1 / std::sqrt(v);
      for (uint32_t e = corners.begin[i]; e < corners.begin[i + 1]; ++e) {
        const size_t f = corners.entry[e] / 3;
        if (!(area[f] > 0)) continue;
        const float* in = integrals.data() + 3 * Ku * f + (corners.entry[e] % 3) * Ku;
        for (Eigen::Index k = 0; k < K; ++k) rhs(r, k) += double(in[k]);
      }
    }
  });
  integrals.clear();
  integrals.shrink_to_fit();
  // Pass 2: the Jacobi-scaled rows, straight into compressed row storage.
  for (size_t r = 0; r < static_cast<size_t>(n); ++r) row_size[r + 1] += row_size[r];
  RowSparseMatrixd M(n, n);
  M.resizeNonZeros(row_size.back());
  for (Eigen::Index r = 0; r <= n; ++r)
    M.outerIndexPtr()[r] =
        static_cast<RowSparseMatrixd::StorageIndex>(row_size[static_cast<size_t>(r)]);
  parallel_range<Eigen::Index>(n, o.threads, 1024, [&](const tbb::blocked_range<Eigen::Index>& range) {
    std::vector<std::pair<Eigen::Index, double>> buf;
    for (Eigen::Index r = range.begin(); r != range.end(); ++r) {
      const uint32_t i = vertex_of[static_cast<size_t>(r)];
      gather_row(i, buf);
      Eigen::Index at = row_size[static_cast<size_t>(r)];
      for (const auto& [j, v] : buf) {
        M.innerIndexPtr()[at] = static_cast<RowSparseMatrixd::StorageIndex>(j);
        M.valuePtr()[at++] = scale[r] * v * scale[j];
      }
    }
  });
  // Solve (S M S) y = S c, x = S y, started at t_u(n_i): the interpolant, a close guess.
  RowMatrixXd y(n, K);
  for (size_t i = 0; i < V; ++i)
    if (slot[i] >= 0)
      for (Eigen::Index k = 0; k < K; ++k) {
        rhs(slot[i], k) *= scale[slot[i]];
        y(slot[i], k) =
            x(static_cast<Eigen::Index>(i), cols[static_cast<size_t>(k)]) / scale[slot[i]];
      }
  BlockCgOptions cg;
  cg.tolerance = o.tolerance, cg.threads = o.threads, cg.max_iterations = 500,
  cg.predict_stall = false;
  const BlockCgResult result = block_conjugate_gradient(M, std::move(rhs), y, cg);
  if (!result.converged)
    throw SolverError(
        "unshadowed projection: the mass matrix did not converge (relative residual " +
        std::to_string(result.relative_residual) + ")");
  for (size_t i = 0; i < V; ++i)
    if (slot[i] >= 0)
      for (Eigen::Index k = 0; k < K; ++k)
        x(static_cast<Eigen::Index>(i), cols[static_cast<size_t>(k)]) =
            scale[slot[i]] * y(slot[i], k);
  st.iterations = result.iterations;
  for (size_t p : points_per_face) st.quadrature_points += p;
  st.seconds = clock.total();
  if (stats) *stats = st;
  return x;
}

}  // namespace prtsub
