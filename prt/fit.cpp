// Least-squares vertex baking (Kavan, Bargteil, Sloan 2011).
//
// The vertex values x define g = Σ h_i x_i, piecewise linear with hat functions h_i over the
// render vertices (each side of a crease its own unknowns, so g may jump there). Minimising
// ∫(f − g)² + α·xᵀRx gives (A + αR) x = b with A_ij = ∫ h_i h_j and b_i = ∫ h_i f; b comes
// from the samples face by face (surface_samples.cpp), A analytically or from the same samples.
// The data term covers only faces that hold samples, so a face without any (zero area, or a
// density too low to reach it) neither pulls its vertices to zero nor claims a value it never saw.
//
// Regularisers, both scale-free like A (entries scale with area):
//  - R_grad: Σ_t a_t ∫|√a_t ∇g|² = Σ_t a_t² G_tᵀG_t. Since ∇h_i = n×e_i/(2a_t) with e_i the
//    edge opposite i, a_t² ∇h_i·∇h_j = e_i·e_j/4: no division by area, so slivers are harmless.
//  - R_edge: for each edge shared, with the same render vertices, by exactly two faces t and u,
//    the squared jump of the derivative across the edge. We measure the jump in the unfolded
//    plane, (d_t + d_u)² with d the derivative along each face's in-plane normal pointing away
//    from the edge: the along-edge derivative is shared, so this is the whole jump, and every
//    function linear on the developed surface costs nothing. The paper weighs a jump by
//    (a_t + a_u)·a with √a-scaled gradients, which for unequal areas penalises linear g and lets a
//    sliver (|∇h| ~ 1/height) swamp the system; we weigh by 2·H², H = 2a_t a_u/(a_t + a_u)
//    the harmonic mean of the areas: the paper's 2a² for equal areas, bounded entries for slivers.
//
// Solving: one sparse LDLᵀ factorisation (AMD ordering) for all K right-hand sides, solved in
// parallel by column. Vertices that no sampled face touches are fixed at their prior (the point
// sample) and moved to the right-hand side. If a pivot still collapses (α = 0 with the sampled
// mass matrix, or faces of area ~1e-16), we add λ·D(x − prior) with D the lumped mass, trying
// λ = 1e-9, 1e-6, 1e-3, 1 until every pivot keeps ten digits; the warning says which was needed.
#include "prt/fit.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/SparseCholesky>
#include <chrono>
#include <cmath>
#include <unordered_map>

#include "subdiv/exceptions.h"

namespace prtsub {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

double seconds_since(std::chrono::steady_clock::time_point& t) {
  auto now = std::chrono::steady_clock::now();
  double s = std::chrono::duration<double>(now - t).count();
  t = now;
  return s;
}

struct FaceGeometry {
  Eigen::Vector3d e[3];  // e[i]: the edge opposite corner i, counter-clockwise
  Eigen::Vector3d n;     // unit normal
  double area = 0;
};

FaceGeometry face_geometry(const Mesh& mesh, const Triangle& t) {
  FaceGeometry g;
  const Eigen::Vector3d p0 = mesh.point(t[0]);
  // Differences first: a mesh far from the origin keeps its precision.
  const Eigen::Vector3d p1 = mesh.point(t[1]) - p0, p2 = mesh.point(t[2]) - p0;
  g.e[0] = p2 - p1, g.e[1] = -p2, g.e[2] = p1;
  const Eigen::Vector3d c = p1.cross(p2);
  g.area = 0.5 * c.norm();
  g.n = g.area > 0 ? Eigen::Vector3d(c.normalized()) : Eigen::Vector3d::Zero();
  return g;
}

// Faces below this area have no usable gradient.
double area_floor(const Mesh& mesh) {
  double total = 0;
  for (const Triangle& t : mesh.triangles) total += face_geometry(mesh, t).area;
  return 1e-14 * total / static_cast<double>(std::max<size_t>(mesh.num_faces(), 1));
}

SparseMatrixd from_triplets(size_t n, const Triplets& t) {
  SparseMatrixd m(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

bool face_has_samples(const SurfaceSamples& s, size_t f) { return f + 1 < s.begin.size() && s.begin[f + 1] > s.begin[f]; }

void check_samples(const Mesh& mesh, const SurfaceSamples& s) {
  if (s.begin.size() != mesh.num_faces() + 1) throw InputError("fit: the samples were drawn on another mesh");
}

}  // namespace

FitMethod parse_fit_method(const std::string& n) {
  if (n == "point") return FitMethod::Point;
  if (n == "average") return FitMethod::Average;
  if (n == "lsq") return FitMethod::LeastSquares;
  throw InputError("--fit must be point, average or lsq, got '" + n + "'");
}
Regularizer parse_regularizer(const std::string& n) {
  if (n == "edge") return Regularizer::Edge;
  if (n == "gradient") return Regularizer::Gradient;
  throw InputError("--regularizer must be edge or gradient, got '" + n + "'");
}
MassMatrix parse_mass_matrix(const std::string& n) {
  if (n == "analytic") return MassMatrix::Analytic;
  if (n == "sampled") return MassMatrix::Sampled;
  throw InputError("--mass must be analytic or sampled, got '" + n + "'");
}
const char* fit_method_name(FitMethod m) {
  return m == FitMethod::Point ? "point" : m == FitMethod::Average ? "average" : "lsq";
}
const char* regularizer_name(Regularizer r) { return r == Regularizer::Edge ? "edge" : "gradient"; }
const char* mass_matrix_name(MassMatrix m) { return m == MassMatrix::Analytic ? "analytic" : "sampled"; }

SparseMatrixd mass_matrix(const Mesh& mesh, const SurfaceSamples& s, MassMatrix kind) {
  check_samples(mesh, s);
  Triplets t;
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    if (!face_has_samples(s, f)) continue;
    const Triangle& tri = mesh.triangles[f];
    if (kind == MassMatrix::Analytic) {
      const double a = face_geometry(mesh, tri).area;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) t.emplace_back(tri[i], tri[j], a / (i == j ? 6.0 : 12.0));
    } else {
      for (size_t k = s.begin[f]; k < s.begin[f + 1]; ++k) {
        const auto r = static_cast<Eigen::Index>(k);
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) t.emplace_back(tri[i], tri[j], s.weight[k] * s.barycentric(r, i) * s.barycentric(r, j));
      }
    }
  }
  return from_triplets(mesh.num_vertices(), t);
}

SparseMatrixd gradient_regularizer(const Mesh& mesh) {
  const double floor = area_floor(mesh);
  Triplets t;
  t.reserve(mesh.num_faces() * 9);
  for (const Triangle& tri : mesh.triangles) {
    const FaceGeometry g = face_geometry(mesh, tri);
    if (!(g.area > floor)) continue;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) t.emplace_back(tri[i], tri[j], 0.25 * g.e[i].dot(g.e[j]));
  }
  return from_triplets(mesh.num_vertices(), t);
}

SparseMatrixd edge_regularizer(const Mesh& mesh, size_t* interior_edges) {
  const double floor = area_floor(mesh);
  // Edges keyed by their render vertices (lower, higher): a crease's two sides never meet here.
  std::unordered_map<uint64_t, std::pair<int64_t, int>> first;  // key -> (face·3 + corner, faces seen)
  first.reserve(mesh.num_faces() * 2);
  std::vector<std::array<int64_t, 2>> pairs;
  auto key = [](uint32_t a, uint32_t b) { return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a; };
  for (size_t f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) {
      const Triangle& tri = mesh.triangles[f];
      auto [it, fresh] = first.try_emplace(key(tri[(c + 1) % 3], tri[(c + 2) % 3]), int64_t(f) * 3 + c, 1);
      if (!fresh && ++it->second.second == 2) pairs.push_back({it->second.first, int64_t(f) * 3 + c});
    }
  Triplets t;
  t.reserve(pairs.size() * 16);
  size_t used = 0;
  for (const auto& pr : pairs) {
    if (first.at(key(mesh.triangles[size_t(pr[0] / 3)][(pr[0] % 3 + 1) % 3],
                     mesh.triangles[size_t(pr[0] / 3)][(pr[0] % 3 + 2) % 3])).second != 2)
      continue;  // non-manifold: no single neighbour to be smooth with
    uint32_t idx[6];
    double q[6];
    double area[2];
    bool ok = true;
    for (int s = 0; s < 2; ++s) {
      const size_t f = size_t(pr[s] / 3);
      const int c = int(pr[s] % 3);  // the corner opposite the shared edge
      const Triangle& tri = mesh.triangles[f];
      const FaceGeometry g = face_geometry(mesh, tri);
      area[s] = g.area;
      if (!(g.area > floor)) {
        ok = false;
        break;
      }
      // In-plane unit normal of the shared edge, pointing into this face (towards corner c).
      const Eigen::Vector3d m = g.n.cross(g.e[c]).normalized();
      for (int i = 0; i < 3; ++i) {
        idx[s * 3 + i] = tri[i];
        q[s * 3 + i] = g.n.cross(g.e[i]).dot(m) / (2 * g.area);  // ∇h_i · m
      }
    }
    if (!ok) continue;
    ++used;
    const double h = 2 * area[0] * area[1] / (area[0] + area[1]);
    const double w = 2 * h * h;
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) t.emplace_back(idx[a], idx[b], w * q[a] * q[b]);
  }
  if (interior_edges) *interior_edges = used;
  return from_triplets(mesh.num_vertices(), t);
}

RowMatrixXd fit_right_hand_side(const Mesh& mesh, const SurfaceSamples& s, const RowMatrixXd& values) {
  check_samples(mesh, s);
  if (static_cast<size_t>(values.rows()) != s.size()) throw InputError("fit: one row of values per sample expected");
  RowMatrixXd b = RowMatrixXd::Zero(static_cast<Eigen::Index>(mesh.num_vertices()), values.cols());
  for (size_t k = 0; k < s.size(); ++k) {
    const Triangle& tri = mesh.triangles[s.face[k]];
    const auto r = static_cast<Eigen::Index>(k);
    for (int i = 0; i < 3; ++i) b.row(tri[i]) += (s.weight[k] * s.barycentric(r, i)) * values.row(r);
  }
  return b;
}

RowMatrixXd fit_vertex_values(const Mesh& mesh, const SurfaceSamples& s, const RowMatrixXd& values,
                              const RowMatrixXd& prior, const FitOptions& o, FitStats* stats_out) {
  FitStats stats;
  const auto V = static_cast<Eigen::Index>(mesh.num_vertices());
  const Eigen::Index K = values.cols();
  if (prior.rows() != V || prior.cols() != K) throw InputError("fit: the prior needs one row per vertex and a column per value");
  if (!(o.alpha >= 0) || !std::isfinite(o.alpha)) throw InputError("--alpha must be finite and non-negative");
  if (!values.allFinite() || !prior.allFinite()) throw InputError("fit: non-finite sample values");
  stats.unknowns = mesh.num_vertices();
  if (o.method == FitMethod::Point) {
    if (stats_out) *stats_out = stats;
    return prior;
  }
  auto clock = std::chrono::steady_clock::now();
  const SparseMatrixd A = mass_matrix(mesh, s, o.mass);
  const RowMatrixXd b = fit_right_hand_side(mesh, s, values);
  Eigen::VectorXd lumped = A * Eigen::VectorXd::Ones(V);
  // A vertex is supported when its lumped mass is a meaningful share of a typical one.
  const double typical = lumped.sum() / static_cast<double>(std::max<Eigen::Index>(V, 1));
  std::vector<char> free(static_cast<size_t>(V));
  for (Eigen::Index i = 0; i < V; ++i) {
    free[size_t(i)] = lumped[i] > 1e-12 * typical;
    stats.unsupported += !free[size_t(i)];
  }

  RowMatrixXd x = prior;
  if (o.method == FitMethod::Average) {
    // Normalised by the samples' own Σ w h_i rather than ∫ h_i: a true weighted average, which
    // stays within the samples' range however few there are.
    const SparseMatrixd As = o.mass == MassMatrix::Sampled ? A : mass_matrix(mesh, s, MassMatrix::Sampled);
    const Eigen::VectorXd weight = As * Eigen::VectorXd::Ones(V);
    for (Eigen::Index i = 0; i < V; ++i)
      if (free[size_t(i)] && weight[i] > 0) x.row(i) = b.row(i) / weight[i];
    stats.seconds_assemble = seconds_since(clock);
    if (stats_out) *stats_out = stats;
    return x;
  }

  SparseMatrixd M = A;
  if (o.alpha > 0) M += o.alpha * (o.regularizer == Regularizer::Edge ? edge_regularizer(mesh) : gradient_regularizer(mesh));
  // Fixed vertices move to the right-hand side; the free ones are renumbered 0..n-1.
  std::vector<Eigen::Index> slot(static_cast<size_t>(V), -1);
  Eigen::Index n = 0;
  for (Eigen::Index i = 0; i < V; ++i)
    if (free[size_t(i)]) slot[size_t(i)] = n++;
  Eigen::MatrixXd rhs(n, K);  // column-major: one contiguous column per solve
  for (Eigen::Index i = 0; i < V; ++i)
    if (slot[size_t(i)] >= 0) rhs.row(slot[size_t(i)]) = b.row(i);
  Triplets t;
  t.reserve(static_cast<size_t>(M.nonZeros()));
  for (Eigen::Index c = 0; c < M.outerSize(); ++c)
    for (SparseMatrixd::InnerIterator it(M, c); it; ++it) {
      const Eigen::Index r = slot[size_t(it.row())], col = slot[size_t(it.col())];
      if (r < 0) continue;
      if (col >= 0) t.emplace_back(r, col, it.value());
      else rhs.row(r) -= it.value() * prior.row(it.col());
    }
  SparseMatrixd system(n, n);
  system.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd dfree(n), prior_term_scale(n);
  for (Eigen::Index i = 0; i < V; ++i)
    if (slot[size_t(i)] >= 0) dfree[slot[size_t(i)]] = lumped[i];
  stats.system_nonzeros = static_cast<size_t>(system.nonZeros());
  stats.seconds_assemble = seconds_since(clock);

  if (n > 0) {
    Eigen::SimplicialLDLT<SparseMatrixd, Eigen::Lower> solver;
    solver.analyzePattern(system);
    // Each pivot of LDLᵀ against the diagonal it came from: ~1e-16 when the system is singular
    // to working precision, and a negative or NaN one when rounding went further.
    auto pivots_hold = [&](const SparseMatrixd& m) {
      if (solver.info() != Eigen::Success) return false;
      const Eigen::VectorXd d = solver.vectorD();
      const Eigen::VectorXd diag = solver.permutationP() * Eigen::VectorXd(m.diagonal());
      for (Eigen::Index i = 0; i < n; ++i)
        if (!(d[i] > 1e-10 * diag[i]) || !std::isfinite(d[i])) return false;
      return true;
    };
    solver.factorize(system);
    bool ok = pivots_hold(system);
    Eigen::MatrixXd stabilised_rhs;
    for (double lambda : {1e-9, 1e-6, 1e-3, 1.0}) {
      if (ok) break;
      SparseMatrixd m = system;
      for (Eigen::Index i = 0; i < n; ++i) m.coeffRef(i, i) += lambda * dfree[i];
      solver.factorize(m);
      ok = pivots_hold(m);
      if (ok) {
        stats.stabilizer = lambda;
        stabilised_rhs = rhs;
        for (Eigen::Index i = 0; i < V; ++i)
          if (slot[size_t(i)] >= 0) stabilised_rhs.row(slot[size_t(i)]) += lambda * lumped[i] * prior.row(i);
      }
    }
    if (!ok) throw SolverError("fit: the least-squares system could not be factorised even when pulled towards the point samples");
    if (stats.stabilizer > 0) {
      rhs.swap(stabilised_rhs);
      stats.warning = "fit: the least-squares system is singular to working precision (alpha " + std::to_string(o.alpha) +
                      ", " + mass_matrix_name(o.mass) + " mass matrix); stabilised towards the point samples with lambda " +
                      std::to_string(stats.stabilizer);
    }
    stats.factor_nonzeros = static_cast<size_t>(solver.matrixL().nestedExpression().nonZeros());
    stats.seconds_factor = seconds_since(clock);
    Eigen::MatrixXd sol(n, K);
    tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
    arena.execute([&] {
      tbb::parallel_for(Eigen::Index(0), K, [&](Eigen::Index k) { sol.col(k) = solver.solve(rhs.col(k)); });
    });
    if (!sol.allFinite()) throw SolverError("fit: the least-squares solve produced non-finite values");
    for (Eigen::Index i = 0; i < V; ++i)
      if (slot[size_t(i)] >= 0) x.row(i) = sol.row(slot[size_t(i)]);
    stats.seconds_solve = seconds_since(clock);
  }
  const double bytes = 12.0 * static_cast<double>(stats.system_nonzeros + stats.factor_nonzeros) +
                       8.0 * 3 * static_cast<double>(n) * static_cast<double>(K);
  stats.solve_memory_mib = bytes / (1024.0 * 1024.0);
  if (stats_out) *stats_out = stats;
  return x;
}

}  // namespace prtsub
