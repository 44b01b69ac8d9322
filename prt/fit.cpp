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
// With the analytic A, b is estimated through a control variate on the prior (the point samples):
// A·prior plus the samples' estimate of ∫h_i (f − g_prior), so its error scales with f − g_prior.
//
// Solving: one CHOLMOD supernodal Cholesky factorisation (AMD ordering) of the Jacobi-scaled
// system for all K right-hand sides. Vertices that no sampled face touches are fixed at their
// prior and moved to the right-hand side. If the factorisation fails or its pivot ratio falls
// below 1e-7 (α = 0 with the sampled mass matrix, faces of area ~1e-16), we add λ·D(x − prior)
// with D the lumped mass, trying λ = 1e-9, 1e-6, 1e-3, 1; the warning says which was needed.
#include "prt/fit.h"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cstdio>
#include <chrono>
#include <cmath>

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

namespace {

std::vector<FaceGeometry> all_face_geometry(const Mesh& mesh) {
  std::vector<FaceGeometry> g(mesh.num_faces());
  for (size_t f = 0; f < g.size(); ++f) g[f] = face_geometry(mesh, mesh.triangles[f]);
  return g;
}

double area_floor(const std::vector<FaceGeometry>& g) {
  double total = 0;
  for (const FaceGeometry& f : g) total += f.area;
  return 1e-14 * total / static_cast<double>(std::max<size_t>(g.size(), 1));
}

// Every matrix below is a sum of small dense blocks; each is emitted entry by entry, both
// triangles, to a sink that either collects triplets or assembles the solver's system.

template <class Emit>
void emit_mass(const Mesh& mesh, const std::vector<FaceGeometry>& g, const SurfaceSamples& s, MassMatrix kind, double scale,
               Emit&& emit) {
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    if (!face_has_samples(s, f)) continue;
    Eigen::Matrix3d local;
    if (kind == MassMatrix::Analytic) {
      local.setConstant(g[f].area / 12);
      local.diagonal().setConstant(g[f].area / 6);
    } else {
      local.setZero();
      for (size_t k = s.begin[f]; k < s.begin[f + 1]; ++k) {
        const Eigen::Vector3d h = s.barycentric.row(static_cast<Eigen::Index>(k)).transpose();
        local += s.weight[k] * h * h.transpose();
      }
    }
    const Triangle& tri = mesh.triangles[f];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) emit(tri[i], tri[j], scale * local(i, j));
  }
}

template <class Emit>
void emit_gradient(const Mesh& mesh, const std::vector<FaceGeometry>& g, double scale, Emit&& emit) {
  const double floor = area_floor(g);
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    if (!(g[f].area > floor)) continue;
    const Triangle& tri = mesh.triangles[f];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) emit(tri[i], tri[j], scale * 0.25 * g[f].e[i].dot(g[f].e[j]));
  }
}

template <class Emit>
size_t emit_edge(const Mesh& mesh, const std::vector<FaceGeometry>& g, double scale, Emit&& emit) {
  const double floor = area_floor(g);
  // Half-edges sorted by their edge's render vertices (lower, higher): a run of exactly two is
  // an interior edge. A crease's two sides have different render vertices and never meet here.
  std::vector<std::pair<uint64_t, uint32_t>> half;
  half.reserve(mesh.num_faces() * 3);
  for (size_t f = 0; f < mesh.num_faces(); ++f)
    for (uint32_t c = 0; c < 3; ++c) {
      const uint32_t a = mesh.triangles[f][(c + 1) % 3], b = mesh.triangles[f][(c + 2) % 3];
      half.emplace_back(a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a, uint32_t(f * 3 + c));
    }
  std::sort(half.begin(), half.end());
  size_t used = 0;
  for (size_t r = 0; r < half.size();) {
    size_t end = r + 1;
    while (end < half.size() && half[end].first == half[r].first) ++end;
    const bool interior = end - r == 2;  // one face is a boundary; three or more are non-manifold
    const size_t first = r;
    r = end;
    if (!interior) continue;
    uint32_t idx[4];
    double q[4] = {0, 0, 0, 0}, area[2];
    int n = 0;
    bool ok = true;
    for (int side = 0; side < 2 && ok; ++side) {
      const uint32_t he = half[first + size_t(side)].second;
      const size_t f = he / 3;
      const int c = int(he % 3);  // the corner opposite the shared edge
      const FaceGeometry& fg = g[f];
      area[side] = fg.area;
      if (!(fg.area > floor)) ok = false;
      if (!ok) break;
      // In-plane unit normal of the shared edge, pointing into this face (towards corner c).
      const Eigen::Vector3d m = fg.n.cross(fg.e[c]).normalized();
      for (int i = 0; i < 3; ++i) {
        const uint32_t v = mesh.triangles[f][i];
        int slot = 0;
        while (slot < n && idx[slot] != v) ++slot;
        if (slot == n) idx[n++] = v;
        q[slot] += fg.n.cross(fg.e[i]).dot(m) / (2 * fg.area);  // ∇h_v · m
      }
    }
    if (!ok || n != 4) continue;
    ++used;
    const double h = 2 * area[0] * area[1] / (area[0] + area[1]);
    const double w = scale * 2 * h * h;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) emit(idx[i], idx[j], w * q[i] * q[j]);
  }
  return used;
}

struct TripletSink {
  Triplets t;
  void operator()(uint32_t i, uint32_t j, double v) { t.emplace_back(i, j, v); }
};

// CHOLMOD's supernodal LLᵀ with access to the factor, for its size and condition.
class Cholesky : public Eigen::CholmodSupernodalLLT<SparseMatrixd, Eigen::Lower> {
 public:
  double rcond() { return m_cholmodFactor ? cholmod_rcond(m_cholmodFactor, &cholmod()) : 0.0; }
  size_t factor_entries() const {
    if (!m_cholmodFactor) return 0;
    return m_cholmodFactor->is_super ? m_cholmodFactor->xsize : m_cholmodFactor->nzmax;
  }
};

}  // namespace

SparseMatrixd mass_matrix(const Mesh& mesh, const SurfaceSamples& s, MassMatrix kind) {
  check_samples(mesh, s);
  TripletSink sink;
  emit_mass(mesh, all_face_geometry(mesh), s, kind, 1.0, sink);
  return from_triplets(mesh.num_vertices(), sink.t);
}

SparseMatrixd gradient_regularizer(const Mesh& mesh) {
  TripletSink sink;
  emit_gradient(mesh, all_face_geometry(mesh), 1.0, sink);
  return from_triplets(mesh.num_vertices(), sink.t);
}

SparseMatrixd edge_regularizer(const Mesh& mesh, size_t* interior_edges) {
  TripletSink sink;
  const size_t used = emit_edge(mesh, all_face_geometry(mesh), 1.0, sink);
  if (interior_edges) *interior_edges = used;
  return from_triplets(mesh.num_vertices(), sink.t);
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
  check_samples(mesh, s);
  const std::vector<FaceGeometry> geom = all_face_geometry(mesh);
  // One pass over the samples, face by face: the lumped masses (∫h_i over sampled faces, and
  // the samples' own Σ_j w_j h_i(p_j)), b = Σ_j w_j h_i(p_j) f(p_j), and for the control
  // variate each face's sampled mass block.
  if (static_cast<size_t>(values.rows()) != s.size()) throw InputError("fit: one row of values per sample expected");
  const bool use_cv = o.method == FitMethod::LeastSquares && o.mass == MassMatrix::Analytic && o.control_variate;
  // b estimates ∫h_i f with an error proportional to f itself, not to its variation, and A⁻¹
  // amplifies it: even a constant f comes back noisy. With the control variate we estimate
  // ∫h_i (f − g_prior) from the samples and add back the exact ∫h_i g_prior = A·prior: the error
  // is then proportional to how far f is from the prior's interpolant. Still unbiased: E[A_s] = A.
  Eigen::VectorXd lumped_analytic = Eigen::VectorXd::Zero(V), lumped_sampled = Eigen::VectorXd::Zero(V);
  RowMatrixXd b = RowMatrixXd::Zero(V, K);
  std::vector<double> local(static_cast<size_t>(3 * K));
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    if (!face_has_samples(s, f)) continue;
    const Triangle& tri = mesh.triangles[f];
    double ls[3] = {0, 0, 0}, ms[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    std::fill(local.begin(), local.end(), 0.0);
    for (size_t k = s.begin[f]; k < s.begin[f + 1]; ++k) {
      const auto r = static_cast<Eigen::Index>(k);
      const double* fv = values.row(r).data();
      for (int c = 0; c < 3; ++c) {
        const double wh = s.weight[k] * s.barycentric(r, c);
        ls[c] += wh;
        for (int c2 = 0; c2 < 3; ++c2) ms[c][c2] += wh * s.barycentric(r, c2);
        double* out = local.data() + c * K;
        for (Eigen::Index q = 0; q < K; ++q) out[q] += wh * fv[q];
      }
    }
    for (int c = 0; c < 3; ++c) {
      lumped_analytic[tri[c]] += geom[f].area / 3;
      lumped_sampled[tri[c]] += ls[c];
      double* row = b.row(tri[c]).data();
      for (Eigen::Index q = 0; q < K; ++q) row[q] += local[size_t(c * K + q)];
      if (!use_cv) continue;
      for (int c2 = 0; c2 < 3; ++c2) {
        const double coeff = geom[f].area / (c == c2 ? 6.0 : 12.0) - ms[c][c2];
        const double* p = prior.row(tri[c2]).data();
        for (Eigen::Index q = 0; q < K; ++q) row[q] += coeff * p[q];
      }
    }
  }
  const Eigen::VectorXd& lumped = o.mass == MassMatrix::Analytic ? lumped_analytic : lumped_sampled;
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
    for (Eigen::Index i = 0; i < V; ++i)
      if (free[size_t(i)] && lumped_sampled[i] > 0) x.row(i) = b.row(i) / lumped_sampled[i];
    stats.seconds_assemble = seconds_since(clock);
    if (stats_out) *stats_out = stats;
    return x;
  }

  // The system over free vertices (renumbered 0..n-1), lower triangle; the fixed ones' columns
  // move to the right-hand side.
  std::vector<Eigen::Index> slot(static_cast<size_t>(V), -1);
  Eigen::Index n = 0;
  for (Eigen::Index i = 0; i < V; ++i)
    if (free[size_t(i)]) slot[size_t(i)] = n++;
  Eigen::MatrixXd rhs(n, K);  // column-major, as CHOLMOD takes it
  for (Eigen::Index i = 0; i < V; ++i)
    if (slot[size_t(i)] >= 0) rhs.row(slot[size_t(i)]) = b.row(i);
  Triplets t;
  t.reserve(mesh.num_faces() * (o.alpha > 0 && o.regularizer == Regularizer::Edge ? 21 : 6));
  auto sink = [&](uint32_t i, uint32_t j, double v) {
    const Eigen::Index si = slot[i], sj = slot[j];
    if (si < 0) return;
    if (sj < 0) rhs.row(si) -= v * prior.row(j);
    else if (si >= sj) t.emplace_back(si, sj, v);
  };
  emit_mass(mesh, geom, s, o.mass, 1.0, sink);
  if (o.alpha > 0) {
    if (o.regularizer == Regularizer::Edge) emit_edge(mesh, geom, o.alpha, sink);
    else emit_gradient(mesh, geom, o.alpha, sink);
  }
  SparseMatrixd system(n, n);
  system.setFromTriplets(t.begin(), t.end());
  Triplets().swap(t);
  // Jacobi scaling: a unit diagonal makes the factor's condition estimate mean "digits lost"
  // whatever the mesh's units and the spread of its triangle sizes.
  Eigen::VectorXd d(n), lumped_free(n);
  for (Eigen::Index i = 0; i < V; ++i)
    if (slot[size_t(i)] >= 0) lumped_free[slot[size_t(i)]] = lumped[i];
  const Eigen::VectorXd diag = system.diagonal();
  for (Eigen::Index i = 0; i < n; ++i) d[i] = diag[i] > 0 ? 1 / std::sqrt(diag[i]) : 1.0;
  system = d.asDiagonal() * system * d.asDiagonal();
  stats.system_nonzeros = static_cast<size_t>(2 * system.nonZeros() - n);
  stats.seconds_assemble = seconds_since(clock);

  if (n > 0) {
    Cholesky solver;
    solver.cholmod().print = 0;  // failures are ours to report, in one line
    solver.analyzePattern(system);
    // Singular, or too ill-conditioned to trust: CHOLMOD stops at a non-positive pivot, or the
    // smallest pivot is below kMinRcond of the largest. (A threshold of 1e-12 let through
    // systems that turned sample noise into errors of 2000% with --mass sampled and 2 samples
    // per triangle; the analytic mass matrix, Jacobi-scaled, stays far above it even with
    // 1e-4° slivers.)
    const double kMinRcond = 1e-7;
    auto holds = [&]() { return solver.info() == Eigen::Success && solver.rcond() > kMinRcond; };
    solver.factorize(system);
    bool ok = holds();
    for (double lambda : {1e-9, 1e-6, 1e-3, 1.0}) {
      if (ok) break;
      SparseMatrixd m = system;
      for (Eigen::Index i = 0; i < n; ++i) m.coeffRef(i, i) += lambda * lumped_free[i] * d[i] * d[i];
      solver.factorize(m);
      ok = holds();
      if (ok) {
        stats.stabilizer = lambda;
        for (Eigen::Index i = 0; i < V; ++i)
          if (slot[size_t(i)] >= 0) rhs.row(slot[size_t(i)]) += lambda * lumped[i] * prior.row(i);
      }
    }
    if (!ok) throw SolverError("fit: the least-squares system could not be factorised even when pulled towards the point samples");
    if (o.mass == MassMatrix::Sampled && static_cast<double>(s.size()) < 8.0 * static_cast<double>(mesh.num_faces()))
      stats.warning = "fit: the sampled mass matrix with under 8 samples per triangle extrapolates vertices that samples barely "
                      "see; errors can be far above point sampling (docs/fit.md). Prefer --mass analytic.";
    if (stats.stabilizer > 0) {
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "fit: the least-squares system is singular to working precision (alpha %g, %s mass matrix); "
                    "stabilised towards the point samples with lambda %g",
                    o.alpha, mass_matrix_name(o.mass), stats.stabilizer);
      stats.warning += (stats.warning.empty() ? "" : " ") + std::string(buf);
    }
    stats.factor_nonzeros = solver.factor_entries();
    stats.seconds_factor = seconds_since(clock);
    const Eigen::MatrixXd sol = d.asDiagonal() * solver.solve(Eigen::MatrixXd(d.asDiagonal() * rhs));
    if (!sol.allFinite()) throw SolverError("fit: the least-squares solve produced non-finite values");
    for (Eigen::Index i = 0; i < V; ++i)
      if (slot[size_t(i)] >= 0) x.row(i) = sol.row(slot[size_t(i)]);
    stats.seconds_solve = seconds_since(clock);
  }
  const double bytes = 12.0 * static_cast<double>(stats.system_nonzeros) / 2 + 8.0 * static_cast<double>(stats.factor_nonzeros) +
                       8.0 * 3 * static_cast<double>(n) * static_cast<double>(K);
  stats.solve_memory_mib = bytes / (1024.0 * 1024.0);
  if (stats_out) *stats_out = stats;
  return x;
}

}  // namespace prtsub
