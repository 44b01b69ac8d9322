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
// The signal arrives as face moments (3 rows of K per face), never per sample. The unknowns are
// numbered breadth-first over the mesh, so a row's neighbours sit in nearby rows whatever the
// file's vertex order; the system is assembled row by row, in parallel, straight into its final
// pattern (each entry summing its terms in one fixed order: the same for any thread count), and
// scaled to a unit diagonal. Vertices that no sampled face touches are fixed at their prior and
// moved to the right-hand side.
//
// Solving: with the analytic mass, block conjugate gradients (block_cg.cpp) started at the prior:
// the scaled mass matrix is well conditioned on any mesh, and CG needs 10–25 passes over the
// matrix to a relative residual of 1e-6, where a Cholesky factor of a 3-D mesh fills in. Rows
// whose diagonal the regulariser holds almost alone (slivers beside large faces in buildings,
// degenerate faces in scans) are stiff: CG solves their block directly in each iteration
// (stiff_block.cpp), which is cheap because they are few and follow the slivers, and then
// converges as on a plain mesh. Only if that block would fill in (a stiff 3-D region: a huge α)
// does CHOLMOD's symbolic analysis of the whole system decide between it and Jacobi CG; all of
// it before any iteration. If CG stalls after all, or with the sampled mass (which can be
// singular), one CHOLMOD supernodal Cholesky factorisation (AMD ordering) for all K right-hand sides. If it fails or its pivot ratio falls below 1e-7 (α = 0 with the sampled
// mass matrix, faces of area ~1e-16), we add λ·D(x − prior) with D the lumped mass, trying
// λ = 1e-9, 1e-6, 1e-3, 1; the warning says which was needed. On request (--solver multigrid),
// CG is preconditioned by a multigrid cycle (multigrid.cpp) built from the functions the
// regulariser does not penalise: its iterations stay flat under refinement, but on the shared
// scenes it is slower than CG or CHOLMOD (BENCHMARKS.md), so the choice above never makes it.
//
// Before the solve, for shadowed transfer (FitOptions::unshadowed_order), a step the paper does
// not have: the prior is corrected by the exact projection of the unshadowed transfer's curvature
// in the interpolated normal, P(w·t_u) − w·t_u(n_i) (unshadowed_projection.cpp), which no vertex
// values interpolate and samples see only through their noise.
//
// After the solve, two more such steps:
//  - Weighing by noise. The point samples (the prior) and the fit are two estimates of each
//    vertex's value: the prior is biased where a face hides what its corners miss, the fit is
//    noisy where its samples carry few rays. Given the prior's variance (from the transfer
//    estimator's two ray halves) and the moments' (Σ (w·h)² var per face corner), four seeded
//    ±1 probe columns, scaled by the moments' standard deviation and solved in the same block,
//    give each vertex's fit variance; each vertex then keeps the share of its correction that
//    minimises the mix's expected squared error.
//  - Non-negativity. A vertex's DC coefficient is clamped at 0 (Constant), and optionally its
//    transfer function is bounded below at 128 directions (Directions), so a non-negative light
//    cannot show negative radiance where the point samples never would.
#include "prtsub/prt/fit.h"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <array>
#include <atomic>
#include <cfloat>
#include <cstdio>
#include <cmath>
#include <stdexcept>
#include <type_traits>

#include <tbb/enumerable_thread_specific.h>

#include "prtsub/prt/block_cg.h"
#include "prtsub/prt/huge_pages.h"
#include "prtsub/prt/multigrid.h"
#include "prtsub/prt/parallel.h"
#include "prtsub/prt/sh.h"
#include "prtsub/prt/stiff_block.h"
#include "prtsub/prt/unshadowed_projection.h"
#include "prtsub/subdiv/adjacency.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

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
bool face_interpolated(const SurfaceSamples& s, size_t f) { return f < s.interpolated.size() && s.interpolated[f]; }

void check_samples(const Mesh& mesh, const SurfaceSamples& s) {
  if (s.begin.size() != mesh.num_faces() + 1 || (!s.interpolated.empty() && s.interpolated.size() != mesh.num_faces()))
    throw InputError("fit: the samples were drawn on another mesh");
}

}  // namespace

FitMethod parse_fit_method(const std::string& n) {
  if (n == "point") return FitMethod::Point;
  if (n == "average") return FitMethod::Average;
  if (n == "lsq") return FitMethod::LeastSquares;
  throw InputError("unknown fit method '" + n + "' (point, average, lsq)");
}
Regularizer parse_regularizer(const std::string& n) {
  if (n == "edge") return Regularizer::Edge;
  if (n == "gradient") return Regularizer::Gradient;
  throw InputError("unknown regularizer '" + n + "' (edge, gradient)");
}
MassMatrix parse_mass_matrix(const std::string& n) {
  if (n == "analytic") return MassMatrix::Analytic;
  if (n == "sampled") return MassMatrix::Sampled;
  throw InputError("unknown mass matrix '" + n + "' (analytic, sampled)");
}
FitSolver parse_fit_solver(const std::string& n) {
  if (n == "auto") return FitSolver::Auto;
  if (n == "cg") return FitSolver::Cg;
  if (n == "multigrid") return FitSolver::Multigrid;
  if (n == "cholmod") return FitSolver::Cholmod;
  throw InputError("unknown fit solver '" + n + "' (auto, cg, multigrid, cholmod)");
}
const char* fit_solver_name(FitSolver s) {
  return s == FitSolver::Auto ? "auto" : s == FitSolver::Cg ? "cg" : s == FitSolver::Multigrid ? "multigrid" : "cholmod";
}
const char* non_negative_name(NonNegative n) {
  return n == NonNegative::Off ? "off" : n == NonNegative::Constant ? "constant" : "directions";
}
const char* fit_method_name(FitMethod m) {
  return m == FitMethod::Point ? "point" : m == FitMethod::Average ? "average" : "lsq";
}
const char* regularizer_name(Regularizer r) { return r == Regularizer::Edge ? "edge" : "gradient"; }
const char* mass_matrix_name(MassMatrix m) { return m == MassMatrix::Analytic ? "analytic" : "sampled"; }

namespace {

HugeVector<FaceGeometry> all_face_geometry(const Mesh& mesh, int threads = 0) {
  HugeVector<FaceGeometry> g(mesh.num_faces());
  parallel_range(g.size(), threads, size_t(4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f < r.end(); ++f) g[f] = face_geometry(mesh, mesh.triangles[f]);
  });
  return g;
}

// body(first, last) for ranges of vertices (by rank) in parallel, each walking every face in one
// fixed order and taking the corners in its range: each vertex sums its terms in the order of one
// serial pass, so the values do not depend on the number of threads.
template <class Body>
void by_vertex_range(size_t V, int threads, Body&& body) {
  const size_t workers = threads > 0 ? size_t(threads) : size_t(tbb::info::default_concurrency());
  const size_t ranges = V < 4096 ? 1 : std::min<size_t>(workers, V / 1024);
  parallel_range(ranges, threads, size_t(1), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) body(V * i / ranges, V * (i + 1) / ranges);
  });
}

// The fit works with every vertex in breadth-first order over the faces (breadth_first_order). A
// scanned mesh's vertex order can be far from its faces' (armadillo: consecutive faces' first
// vertices lie a median 25,302 apart: bench/vertex_order.py); in this order a vertex's
// neighbours, and the faces around it, sit nearby in memory: in CG's passes over the rows and
// in the assembly's walks over the faces. The faces, by their lowest-ranked corner:
std::vector<uint32_t> faces_in_rank_order(const Mesh& mesh, const std::vector<uint32_t>& rank) {
  const std::vector<Triangle>& t = mesh.triangles;
  return bucket_sort(mesh.num_vertices(), t.size(), 1, [&](size_t f, uint32_t) {
           return std::min({rank[t[f][0]], rank[t[f][1]], rank[t[f][2]]});
         }).entry;
}

// Row c of a sampled face's mass block, Σ_k w_k h_c(p_k) h_j(p_k), and its lumped mass Σ_k w_k h_c(p_k).
double sampled_mass_row(const SurfaceSamples& s, size_t f, int c, double row[3]) {
  double lumped = 0;
  row[0] = row[1] = row[2] = 0;
  for (size_t k = s.begin[f]; k < s.begin[f + 1]; ++k) {
    const auto r = static_cast<Eigen::Index>(k);
    const double wh = s.weight[k] * s.barycentric(r, c);
    lumped += wh;
    for (int j = 0; j < 3; ++j) row[j] += wh * s.barycentric(r, j);
  }
  return lumped;
}

double area_floor(const HugeVector<FaceGeometry>& g) {
  double total = 0;
  for (const FaceGeometry& f : g) total += f.area;
  return 1e-14 * total / static_cast<double>(std::max<size_t>(g.size(), 1));
}

// Every matrix below is a sum of small dense blocks; each is emitted entry by entry, both
// triangles, to a sink that either collects triplets or assembles the solver's system.

template <class Emit>
void emit_mass(const Mesh& mesh, const HugeVector<FaceGeometry>& g, const SurfaceSamples& s, MassMatrix kind, double scale,
               Emit&& emit) {
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    const bool interpolated = face_interpolated(s, f);
    if (!interpolated && !face_has_samples(s, f)) continue;
    Eigen::Matrix3d local;
    if (kind == MassMatrix::Analytic || interpolated) {  // an interpolated face's data is exact
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
void emit_gradient(const Mesh& mesh, const HugeVector<FaceGeometry>& g, double scale, Emit&& emit) {
  const double floor = area_floor(g);
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    if (!(g[f].area > floor)) continue;
    const Triangle& tri = mesh.triangles[f];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) emit(tri[i], tri[j], scale * 0.25 * g[f].e[i].dot(g[f].e[j]));
  }
}

// Interior edges: shared, with the same render vertices (lower, higher), by exactly two faces;
// each as its two half-edges f·3 + c, c the corner opposite the edge. A boundary edge has one
// face, a non-manifold one three or more; a crease's two sides have different render vertices.
using EdgePairs = HugeVector<std::array<uint32_t, 2>>;
EdgePairs interior_edge_pairs(const Mesh& mesh) {
  const EdgeAdjacency adj = edge_adjacency(mesh.triangles);
  EdgePairs pairs;
  pairs.reserve(adj.num_edges());
  auto opposite = [](uint32_t h) { return h / 3 * 3 + (h % 3 + 2) % 3; };  // the corner across from h
  for (size_t e = 0; e < adj.num_edges(); ++e)
    if (adj.valence(e) == 2) pairs.push_back({opposite(adj.edge_begin(e)[0]), opposite(adj.edge_begin(e)[1])});
  return pairs;
}

// One interior edge's 4×4 block w·q qᵀ over the four vertices of its two faces; `used` is false
// when a face is degenerate or the two faces do not span four distinct vertices.
struct EdgeBlock {
  uint32_t idx[4] = {0, 0, 0, 0};
  double q[4] = {0, 0, 0, 0};
  double w = 0;
  bool used = false;
};

EdgeBlock edge_block(const Mesh& mesh, const HugeVector<FaceGeometry>& g, const std::array<uint32_t, 2>& edge, double floor,
                     double scale) {
  EdgeBlock b;
  double area[2];
  int n = 0;
  for (int side = 0; side < 2; ++side) {
    const uint32_t he = edge[size_t(side)];
    const size_t f = he / 3;
    const int c = int(he % 3);  // the corner opposite the shared edge
    const FaceGeometry& fg = g[f];
    area[side] = fg.area;
    if (!(fg.area > floor)) return b;
    // In-plane unit normal of the shared edge, pointing into this face (towards corner c).
    const Eigen::Vector3d m = fg.n.cross(fg.e[c]).normalized();
    for (int i = 0; i < 3; ++i) {
      const uint32_t v = mesh.triangles[f][i];
      int slot = 0;
      while (slot < n && b.idx[slot] != v) ++slot;
      if (slot == 4) return b;  // not two faces on one edge
      if (slot == n) b.idx[n++] = v;
      b.q[slot] += fg.n.cross(fg.e[i]).dot(m) / (2 * fg.area);  // ∇h_v · m
    }
  }
  if (n != 4) return b;
  const double h = 2 * area[0] * area[1] / (area[0] + area[1]);
  b.w = scale * 2 * h * h;
  b.used = true;
  return b;
}

template <class Emit>
size_t emit_edge(const Mesh& mesh, const HugeVector<FaceGeometry>& g, const EdgePairs& edges, double scale, Emit&& emit) {
  const double floor = area_floor(g);
  size_t used = 0;
  for (const auto& edge : edges) {
    const EdgeBlock b = edge_block(mesh, g, edge, floor, scale);
    if (!b.used) continue;
    ++used;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) emit(b.idx[i], b.idx[j], b.w * b.q[i] * b.q[j]);
  }
  return used;
}

// The used blocks by their first row (the least slot of their free vertices; ties keep edge
// order): a row's blocks then lie near each other and near its neighbours' rows, as the
// breadth-first numbering does for the rows themselves.
HugeVector<EdgeBlock> in_row_order(const HugeVector<EdgeBlock>& blocks, const std::vector<Eigen::Index>& slot, Eigen::Index n) {
  const Buckets rows = bucket_sort(size_t(n) + 1, blocks.size(), 1, [&](size_t e, uint32_t) {
    if (!blocks[e].used) return Buckets::kNone;
    Eigen::Index r = n;
    for (uint32_t v : blocks[e].idx)
      if (slot[v] >= 0) r = std::min(r, slot[v]);
    return static_cast<uint32_t>(r);
  });
  HugeVector<EdgeBlock> sorted(rows.entry.size());
  for (size_t i = 0; i < sorted.size(); ++i) sorted[i] = blocks[rows.entry[i]];
  return sorted;
}

// Each vertex's (edge block, corner of the block) pairs 4e + i, in increasing block order.
Buckets vertex_edges(size_t V, const HugeVector<EdgeBlock>& blocks) {
  return bucket_sort(V, blocks.size(), 4, [&](size_t e, uint32_t i) { return blocks[e].used ? blocks[e].idx[i] : Buckets::kNone; });
}

// The system's rows, row si for vertex order[si], both triangles, columns sorted: each row's
// terms are gathered from its vertex's corners (faces in increasing order: the mass, then the
// gradient term) and edge blocks in a fixed order, and each entry sums its own in that order,
// so the values do not depend on the number of threads. A term on a vertex fixed at its prior
// goes to the right-hand side instead (emit_fixed). Two passes over the rows, each in parallel:
// the first counts each row's distinct columns (the terms' columns only, no values), which lays
// out the matrix; the second writes every row straight into its place. This replaced per-chunk
// buffers copied into the matrix afterwards: the same time within the machine's noise
// (BENCHMARKS.md, "What grows faster than the mesh"), without the buffers' memory.
template <class Terms, class Fixed>
RowSparseMatrixd assemble_rows(Eigen::Index n, int threads, Terms&& terms, Fixed&& emit_fixed) {
  constexpr Eigen::Index kGrain = 1024;
  struct Scratch {
    std::vector<std::pair<int, double>> terms;
    std::vector<int> position, distinct;
  };
  tbb::enumerable_thread_specific<Scratch> scratch([n] { return Scratch{{}, std::vector<int>(size_t(n), -1), {}}; });
  RowSparseMatrixd m(n, n);
  int* outer = m.outerIndexPtr();
  parallel_range(n, threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& r) {
    Scratch& w = scratch.local();
    for (Eigen::Index si = r.begin(); si < r.end(); ++si) {
      w.distinct.clear();
      terms(si, std::false_type(), [&](Eigen::Index sj, uint32_t, double) {
        if (sj >= 0 && w.position[size_t(sj)] < 0) w.position[size_t(sj)] = 0, w.distinct.push_back(static_cast<int>(sj));
      });
      for (int col : w.distinct) w.position[size_t(col)] = -1;
      outer[si + 1] = static_cast<int>(w.distinct.size());
    }
  });
  outer[0] = 0;
  for (Eigen::Index si = 0; si < n; ++si) outer[si + 1] += outer[si];
  m.resizeNonZeros(outer[n]);
  prefer_huge_pages(m.valuePtr(), size_t(outer[n]) * sizeof(double));
  prefer_huge_pages(m.innerIndexPtr(), size_t(outer[n]) * sizeof(int));
  parallel_range(n, threads, kGrain, [&](const tbb::blocked_range<Eigen::Index>& r) {
    Scratch& w = scratch.local();
    for (Eigen::Index si = r.begin(); si < r.end(); ++si) {
      w.terms.clear(), w.distinct.clear();
      terms(si, std::true_type(), [&](Eigen::Index sj, uint32_t j, double x) {
        if (sj < 0) emit_fixed(si, j, x);
        else w.terms.emplace_back(static_cast<int>(sj), x);
      });
      for (const auto& t : w.terms)
        if (w.position[size_t(t.first)] < 0) w.position[size_t(t.first)] = 0, w.distinct.push_back(t.first);
      if (static_cast<int>(w.distinct.size()) != outer[si + 1] - outer[si])
        throw std::logic_error("fit: a row's columns changed between the assembly's two passes");
      std::sort(w.distinct.begin(), w.distinct.end());
      for (size_t k = 0; k < w.distinct.size(); ++k) w.position[size_t(w.distinct[k])] = static_cast<int>(k);
      double* value = m.valuePtr() + outer[si];
      std::fill(value, value + w.distinct.size(), 0.0);
      for (const auto& t : w.terms) value[w.position[size_t(t.first)]] += t.second;
      for (int col : w.distinct) w.position[size_t(col)] = -1;
      std::copy(w.distinct.begin(), w.distinct.end(), m.innerIndexPtr() + outer[si]);
    }
  });
  return m;
}

struct TripletSink {
  Triplets t;
  void operator()(uint32_t i, uint32_t j, double v) { t.emplace_back(i, j, v); }
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
  const size_t used = emit_edge(mesh, all_face_geometry(mesh), interior_edge_pairs(mesh), 1.0, sink);
  if (interior_edges) *interior_edges = used;
  return from_triplets(mesh.num_vertices(), sink.t);
}

void sample_moments(const SurfaceSamples& s, size_t first, size_t last, const double* values, Eigen::Index K, double* out) {
  std::fill(out, out + 3 * K, 0.0);
  for (size_t k = first; k < last; ++k, values += K)
    for (int c = 0; c < 3; ++c) {
      const double wh = s.weight[k] * s.barycentric(static_cast<Eigen::Index>(k), c);
      double* o = out + c * K;
      for (Eigen::Index q = 0; q < K; ++q) o[q] += wh * values[q];
    }
}

FaceMoments merge_face_moments(const SurfaceSamples& a, const FaceMoments& ma, const SurfaceSamples& b, const FaceMoments& mb) {
  const size_t F = a.begin.empty() ? 0 : a.begin.size() - 1;
  if (b.begin.size() != a.begin.size() || size_t(ma.rows.rows()) != 3 * F || size_t(mb.rows.rows()) != 3 * F ||
      ma.rows.cols() != mb.rows.cols() || ma.variance.size() != mb.variance.size())
    throw InputError("fit: cannot merge the moments of different sample sets");
  FaceMoments m{RowMatrixXd(ma.rows.rows(), ma.rows.cols()), std::vector<double>(ma.variance.size(), 0.0)};
  for (size_t f = 0; f < F; ++f) {
    const double na = double(a.begin[f + 1] - a.begin[f]), nb = double(b.begin[f + 1] - b.begin[f]);
    const double wa = na + nb > 0 ? na / (na + nb) : 0, wb = na + nb > 0 ? nb / (na + nb) : 0;
    const auto r = static_cast<Eigen::Index>(3 * f);
    m.rows.middleRows(r, 3) = wa * ma.rows.middleRows(r, 3) + wb * mb.rows.middleRows(r, 3);
    if (!m.variance.empty())
      for (size_t k = 3 * f; k < 3 * f + 3; ++k) m.variance[k] = wa * wa * ma.variance[k] + wb * wb * mb.variance[k];
  }
  return m;
}

FaceMoments face_moments(const Mesh& mesh, const SurfaceSamples& s, const RowMatrixXd& values) {
  check_samples(mesh, s);
  if (static_cast<size_t>(values.rows()) != s.size()) throw InputError("fit: one row of values per sample expected");
  const Eigen::Index K = values.cols();
  FaceMoments m{RowMatrixXd(static_cast<Eigen::Index>(3 * mesh.num_faces()), K), {}};
  for (size_t f = 0; f < mesh.num_faces(); ++f)
    sample_moments(s, s.begin[f], s.begin[f + 1], values.data() + static_cast<Eigen::Index>(s.begin[f]) * K, K,
                   m.rows.row(static_cast<Eigen::Index>(3 * f)).data());
  return m;
}

RowMatrixXd fit_right_hand_side(const Mesh& mesh, const SurfaceSamples& s, const RowMatrixXd& values) {
  const FaceMoments m = face_moments(mesh, s, values);
  RowMatrixXd b = RowMatrixXd::Zero(static_cast<Eigen::Index>(mesh.num_vertices()), values.cols());
  for (size_t f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) b.row(mesh.triangles[f][c]) += m.rows.row(static_cast<Eigen::Index>(3 * f + size_t(c)));
  return b;
}

RowMatrixXd fit_vertex_values(const Mesh& mesh, const SurfaceSamples& s, const RowMatrixXd& values, const RowMatrixXd& prior,
                              const FitOptions& o, FitStats* stats_out) {
  return fit_vertex_values(mesh, s, face_moments(mesh, s, values), prior, o, stats_out);
}

namespace {

// Per vertex, over its corners: the lumped masses (∫h_i over sampled faces, and the samples' own
// Σ_j w_j h_i(p_j)) and b from the face moments, with the control variate's correction.
struct FaceSums {
  Eigen::VectorXd lumped_analytic, lumped_sampled;
  //! ∫h_i over the faces with samples only: a vertex without any keeps its prior, since faces
  //! left to interpolation (SurfaceSamples::interpolated) say only that the prior is right there
  Eigen::VectorXd support;
  RowMatrixXd b;  // #V by K; zero where no sampled face touches the vertex (it keeps its prior)
};  // (each indexed by the vertex's rank, see sum_faces)

// Indexed by rank (vertex order[r] has rank r): each range of ranks walks the faces in
// face_order, so a vertex sums its terms in that fixed order whatever the number of threads.
// prior_ranked: the prior's rows in rank order.
FaceSums sum_faces(const Mesh& mesh, const SurfaceSamples& s, const HugeVector<FaceGeometry>& geom, const FaceMoments& moments,
                   const RowMatrixXd& prior_ranked, const std::vector<uint32_t>& rank, const std::vector<uint32_t>& face_order,
                   const FitOptions& o) {
  const auto V = static_cast<Eigen::Index>(mesh.num_vertices());
  const Eigen::Index K = moments.rows.cols();
  // b estimates ∫h_i f with an error proportional to f itself, not to its variation, and A⁻¹
  // amplifies it: even a constant f comes back noisy. With the control variate we estimate
  // ∫h_i (f − g_prior) from the samples and add back the exact ∫h_i g_prior = A·prior: the error
  // is then proportional to how far f is from the prior's interpolant. Still unbiased: E[A_s] = A.
  const bool use_cv = o.method == FitMethod::LeastSquares && o.mass == MassMatrix::Analytic && o.control_variate;
  FaceSums sums{Eigen::VectorXd::Zero(V), Eigen::VectorXd::Zero(V), Eigen::VectorXd::Zero(V), RowMatrixXd(V, K)};
  prefer_huge_pages(sums.b);
  sums.b.setZero();
  // Each sampled face's three rows of its samples' own mass and their lumped masses, once per
  // face (the vertex ranges below would read the samples once per corner).
  // (Stored for the sampled faces only: with the pilot, a few percent of them.)
  std::vector<uint32_t> sampled(mesh.num_faces(), UINT32_MAX);
  uint32_t count = 0;
  for (size_t f = 0; f < mesh.num_faces(); ++f)
    if (!face_interpolated(s, f) && face_has_samples(s, f)) sampled[f] = count++;
  HugeVector<std::array<double, 4>> corner_mass(3 * size_t(count));
  parallel_range(mesh.num_faces(), o.threads, size_t(1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f < r.end(); ++f)
      if (sampled[f] != UINT32_MAX)
        for (int c = 0; c < 3; ++c) {
          std::array<double, 4>& m = corner_mass[3 * size_t(sampled[f]) + size_t(c)];
          m[3] = sampled_mass_row(s, f, c, m.data());
        }
  });
  // The faces' corners by rank, in walk order: every range reads them, so they are looked up once.
  HugeVector<std::array<uint32_t, 3>> ranked(face_order.size());
  parallel_range(face_order.size(), o.threads, size_t(4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      for (int c = 0; c < 3; ++c) ranked[i][size_t(c)] = rank[mesh.triangles[face_order[i]][size_t(c)]];
  });
  // Vertices with a sampled face around them: only they can be unknowns, so only their b is
  // summed (with the pilot, most faces are left to interpolation and most vertices keep their prior).
  std::vector<char> touched(static_cast<size_t>(V), 0);
  for (size_t i = 0; i < face_order.size(); ++i)
    if (!face_interpolated(s, face_order[i]) && face_has_samples(s, face_order[i]))
      for (uint32_t v : ranked[i]) touched[v] = 1;
  by_vertex_range(size_t(V), o.threads, [&](size_t first, size_t last) {
    for (size_t i = 0; i < face_order.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        const uint32_t v = ranked[i][size_t(c)];
        if (v < first || v >= last) continue;
        const size_t f = face_order[i];
        const std::array<uint32_t, 3>& tri = ranked[i];
        double* row = sums.b.row(v).data();
        if (face_interpolated(s, f)) {
          // No samples, by design: the face's data is the prior's interpolant, so it adds
          // ∫h_i g_prior = A_f·prior exactly, and its mass to both lumped masses.
          sums.lumped_analytic[v] += geom[f].area / 3;
          sums.lumped_sampled[v] += geom[f].area / 3;
          if (!touched[v]) continue;
          for (int c2 = 0; c2 < 3; ++c2) {
            const double coeff = geom[f].area / (c == c2 ? 6.0 : 12.0);
            const double* p = prior_ranked.row(tri[size_t(c2)]).data();
            for (Eigen::Index q = 0; q < K; ++q) row[q] += coeff * p[q];
          }
          continue;
        }
        if (!face_has_samples(s, f)) continue;
        const double* ms = corner_mass[3 * size_t(sampled[f]) + size_t(c)].data();
        sums.lumped_analytic[v] += geom[f].area / 3;
        sums.lumped_sampled[v] += ms[3];
        sums.support[v] += geom[f].area / 3;
        const double* local = moments.rows.row(static_cast<Eigen::Index>(3 * f + size_t(c))).data();
        for (Eigen::Index q = 0; q < K; ++q) row[q] += local[q];
        if (!use_cv) continue;
        for (int c2 = 0; c2 < 3; ++c2) {
          const double coeff = geom[f].area / (c == c2 ? 6.0 : 12.0) - ms[c2];
          const double* p = prior_ranked.row(tri[size_t(c2)]).data();
          for (Eigen::Index q = 0; q < K; ++q) row[q] += coeff * p[q];
        }
      }
  });
  return sums;
}

// Whether every value is finite, by row blocks in parallel: the moments are the fit's largest
// input, and Eigen's allFinite made a serial pass over them.
bool all_finite(const RowMatrixXd& m, int threads) {
  std::atomic<bool> ok{true};
  parallel_range(m.rows(), threads, Eigen::Index(4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
    bool good = true;
    for (const double* p = m.data() + r.begin() * m.cols(); p != m.data() + r.end() * m.cols(); ++p) good &= std::abs(*p) <= DBL_MAX;
    if (!good) ok = false;
  });
  return ok;
}

// The moment rows any fit reads: those of faces with samples. The others are zero and never
// read, and on a dense mesh with the pilot they are nearly all of them: the matrix is allocated
// zeroed, untouched by the kernel until read, and a pass over it made the kernel back all of it
// (most of armadillo refined to 1.5M triangles' peak, 1753 → 1077 MiB: BENCHMARKS.md).
bool sampled_moments_finite(const SurfaceSamples& s, const FaceMoments& m, int threads) {
  std::atomic<bool> ok{true};
  const Eigen::Index K = m.rows.cols();
  parallel_range(s.begin.size() - 1, threads, size_t(4096), [&](const tbb::blocked_range<size_t>& r) {
    bool good = true;
    for (size_t f = r.begin(); f < r.end(); ++f) {
      if (!face_has_samples(s, f)) continue;
      const double* p = m.rows.data() + static_cast<Eigen::Index>(3 * f) * K;
      for (Eigen::Index k = 0; k < 3 * K; ++k) good &= std::abs(p[k]) <= DBL_MAX;
    }
    if (!good) ok = false;
  });
  return ok;
}

void check_fit_inputs(const Mesh& mesh, const SurfaceSamples& s, const FaceMoments& moments, const RowMatrixXd& prior,
                      const FitOptions& o) {
  const auto V = static_cast<Eigen::Index>(mesh.num_vertices());
  if (prior.rows() != V || prior.cols() != moments.rows.cols())
    throw InputError("fit: the prior needs one row per vertex and a column per value");
  if (!(o.alpha >= 0) || !std::isfinite(o.alpha)) throw InputError("fit: alpha must be finite and non-negative, got " + std::to_string(o.alpha));
  if (!(o.stiff_mass >= 0 && o.stiff_mass <= 1)) throw InputError("fit: the stiff rows' mass share must be in [0, 1], got " + std::to_string(o.stiff_mass));
  check_samples(mesh, s);
  if (static_cast<size_t>(moments.rows.rows()) != 3 * mesh.num_faces()) throw InputError("fit: three rows of moments per face expected");
  if (!sampled_moments_finite(s, moments, o.threads) || !all_finite(prior, o.threads)) throw InputError("fit: non-finite sample values");
}

// x = D⁻¹b, D the samples' own lumped mass: a true weighted average, which stays within the
// samples' range however few there are.
RowMatrixXd average_values(const FaceSums& sums, const std::vector<char>& free, const RowMatrixXd& prior) {
  RowMatrixXd x = prior;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if (free[size_t(i)] && sums.lumped_sampled[i] > 0) x.row(i) = sums.b.row(i) / sums.lumped_sampled[i];
  return x;
}

}  // namespace

FitSystem assemble_fit_system(const Mesh& mesh, const SurfaceSamples& s, const FaceMoments& moments, const RowMatrixXd& prior,
                              const FitOptions& o, FitStats* stats) {
  check_fit_inputs(mesh, s, moments, prior, o);
  const Stopwatch clock;
  Stopwatch part;  // the parts' seconds for FitStats
  double seconds_sums = 0, seconds_edges = 0, seconds_rows = 0;
  const auto V = static_cast<Eigen::Index>(mesh.num_vertices());
  const Eigen::Index K = moments.rows.cols();
  const HugeVector<FaceGeometry> geom = all_face_geometry(mesh, o.threads);
  const Buckets corners = vertex_corners(mesh.triangles, mesh.num_vertices());
  const std::vector<uint32_t> by_rank = breadth_first_order(mesh.triangles, corners, mesh.num_vertices());
  std::vector<uint32_t> rank(static_cast<size_t>(V));
  for (uint32_t r = 0; r < by_rank.size(); ++r) rank[by_rank[r]] = r;
  RowMatrixXd prior_ranked(V, K);
  prefer_huge_pages(prior_ranked);
  parallel_range(V, o.threads, Eigen::Index(4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
    for (Eigen::Index i = r.begin(); i < r.end(); ++i) prior_ranked.row(i) = prior.row(by_rank[size_t(i)]);
  });
  part.lap();
  FaceSums sums = sum_faces(mesh, s, geom, moments, prior_ranked, rank, faces_in_rank_order(mesh, rank), o);
  seconds_sums = part.lap();
  const Eigen::VectorXd& lumped = o.mass == MassMatrix::Analytic ? sums.lumped_analytic : sums.lumped_sampled;
  // A vertex is free when its lumped mass is a meaningful share of a typical one; the others keep
  // their prior, and their columns move to the right-hand side.
  const double typical = lumped.sum() / static_cast<double>(std::max<Eigen::Index>(V, 1));
  FitSystem sys;
  // The unknowns: the free vertices in rank order. (sums are by rank.)
  std::vector<uint32_t> order;  // slot → vertex
  sys.slot.assign(static_cast<size_t>(V), -1);
  for (Eigen::Index r = 0; r < V; ++r)
    if (lumped[r] > 1e-12 * typical && sums.support[r] > 1e-12 * typical)
      sys.slot[by_rank[size_t(r)]] = static_cast<Eigen::Index>(order.size()), order.push_back(by_rank[size_t(r)]);
  const auto n = static_cast<Eigen::Index>(order.size());
  if (n == V) {
    sys.rhs.swap(sums.b);  // every vertex free, the common case: no copy
  } else {
    sys.rhs.resize(n, K);
    for (Eigen::Index r = 0; r < V; ++r)
      if (sys.slot[by_rank[size_t(r)]] >= 0) sys.rhs.row(sys.slot[by_rank[size_t(r)]]) = sums.b.row(r);
  }
  // Straight into the final pattern: no triplets, whose memory costs more than their arithmetic.
  const bool edge_term = o.alpha > 0 && o.regularizer == Regularizer::Edge;
  const EdgePairs edges = edge_term ? interior_edge_pairs(mesh) : EdgePairs();
  const double floor = area_floor(geom);
  // Only the edges with an unknown among their four vertices (with the pilot, a few percent).
  std::vector<char> live(edges.size(), 0);
  parallel_range(edges.size(), o.threads, size_t(4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t e = r.begin(); e < r.end(); ++e)
      for (uint32_t he : edges[e])
        for (uint32_t v : mesh.triangles[he / 3]) live[e] |= sys.slot[v] >= 0;
  });
  std::vector<uint32_t> live_edges;
  for (uint32_t e = 0; e < edges.size(); ++e)
    if (live[e]) live_edges.push_back(e);
  HugeVector<EdgeBlock> blocks(live_edges.size());
  parallel_range(live_edges.size(), o.threads, size_t(4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) blocks[i] = edge_block(mesh, geom, edges[live_edges[i]], floor, o.alpha);
  });
  blocks = in_row_order(blocks, sys.slot, n);  // (the used ones)
  const Buckets vertex_blocks = vertex_edges(size_t(V), blocks);
  seconds_edges = part.lap();
  // (values: std::true_type, or false_type for the columns alone, whose values are then unused)
  auto terms = [&](Eigen::Index si, auto values, auto&& add_term) {
    constexpr bool kValues = decltype(values)::value;
    const uint32_t v = order[size_t(si)];
    auto add = [&](uint32_t j, double x) { add_term(sys.slot[j], j, x); };
    const uint32_t* first = corners.entry.data() + corners.begin[v];
    const uint32_t* last = corners.entry.data() + corners.begin[v + 1];
    for (const uint32_t* h = first; h != last; ++h) {
      const size_t f = *h / 3;
      const int c = int(*h % 3);
      const bool interpolated = face_interpolated(s, f);
      if (!interpolated && !face_has_samples(s, f)) continue;
      const Triangle& tri = mesh.triangles[f];
      if (o.mass == MassMatrix::Analytic || interpolated) {  // an interpolated face's data is exact
        for (int j = 0; j < 3; ++j) add(tri[j], geom[f].area / (j == c ? 6 : 12));
      } else {
        double row[3] = {0, 0, 0};
        if constexpr (kValues) sampled_mass_row(s, f, c, row);
        for (int j = 0; j < 3; ++j) add(tri[j], row[j]);
      }
    }
    if (o.alpha > 0 && !edge_term)
      for (const uint32_t* h = first; h != last; ++h) {
        const size_t f = *h / 3;
        const int c = int(*h % 3);
        if (!(geom[f].area > floor)) continue;
        for (int j = 0; j < 3; ++j) add(mesh.triangles[f][j], o.alpha * 0.25 * geom[f].e[c].dot(geom[f].e[j]));
      }
    if (edge_term)
      for (uint32_t k = vertex_blocks.begin[v]; k < vertex_blocks.begin[v + 1]; ++k) {
        const EdgeBlock& b = blocks[vertex_blocks.entry[k] / 4];
        const uint32_t i = vertex_blocks.entry[k] % 4;
        for (int j = 0; j < 4; ++j) add(b.idx[j], b.w * b.q[i] * b.q[j]);
      }
  };
  // A term on a vertex fixed at its prior moves to the right-hand side (rows of distinct si:
  // no two workers share one).
  auto fixed = [&](Eigen::Index si, uint32_t j, double x) {
    double* rhs = sys.rhs.row(si).data();
    const double* p = prior.row(j).data();
    for (Eigen::Index q = 0; q < K; ++q) rhs[q] -= x * p[q];
  };
  sys.matrix = assemble_rows(n, o.threads, terms, fixed);
  seconds_rows = part.lap();
  const int* outer = sys.matrix.outerIndexPtr();
  const int* inner = sys.matrix.innerIndexPtr();
  double* value = sys.matrix.valuePtr();
  // Jacobi scaling: a unit diagonal makes the factor's condition estimate mean "digits lost"
  // whatever the mesh's units and the spread of its triangle sizes, and is CG's preconditioner.
  sys.scale.resize(n);
  sys.lumped.resize(n);
  for (Eigen::Index r = 0; r < V; ++r)
    if (sys.slot[by_rank[size_t(r)]] >= 0) sys.lumped[sys.slot[by_rank[size_t(r)]]] = lumped[r];
  if (o.solver == FitSolver::Multigrid) {
    // Positions relative to the mesh's centre, in units of its size: near-null vectors that stay
    // well conditioned however far from the origin the mesh lies. Only the multigrid reads them.
    Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY), high = -low;
    for (uint32_t v : order) low = low.cwiseMin(mesh.point(v)), high = high.cwiseMax(mesh.point(v));
    const Eigen::Vector3d centre = 0.5 * (low + high);
    const double size = n ? std::max((high - low).maxCoeff(), DBL_MIN) : 1.0;
    sys.points.resize(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) sys.points.row(i) = ((mesh.point(order[size_t(i)]) - centre) / size).transpose();
  }
  parallel_range(n, o.threads, Eigen::Index(4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
    for (Eigen::Index i = r.begin(); i < r.end(); ++i) {
      double d = 0;
      for (int k = outer[i]; k < outer[i + 1]; ++k)
        if (inner[k] == i) d = value[k];
      sys.scale[i] = d > 0 ? 1 / std::sqrt(d) : 1.0;
    }
  });
  parallel_range(n, o.threads, Eigen::Index(4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
    for (Eigen::Index i = r.begin(); i < r.end(); ++i) {
      for (int k = outer[i]; k < outer[i + 1]; ++k) value[k] *= sys.scale[i] * sys.scale[inner[k]];
      for (Eigen::Index q = 0; q < K; ++q) sys.rhs(i, q) *= sys.scale[i];
    }
  });
  if (stats) {
    stats->unknowns = mesh.num_vertices();
    stats->unsupported = static_cast<size_t>(V - n);
    stats->system_nonzeros = static_cast<size_t>(sys.matrix.nonZeros());
    stats->seconds_assemble = clock.total();
    stats->seconds_assemble_sums = seconds_sums, stats->seconds_assemble_edges = seconds_edges;
    stats->seconds_assemble_rows = seconds_rows;
  }
  return sys;
}

// CHOLMOD's supernodal LLᵀ with access to the factor, for its size and condition.
class FitSystemSolver::Cholesky : public Eigen::CholmodSupernodalLLT<SparseMatrixd, Eigen::Lower> {
 public:
  double rcond() { return m_cholmodFactor ? cholmod_rcond(m_cholmodFactor, &cholmod()) : 0.0; }
  size_t factor_entries() const {
    if (!m_cholmodFactor) return 0;
    return m_cholmodFactor->is_super ? m_cholmodFactor->xsize : m_cholmodFactor->nzmax;
  }
};

namespace {

// The block is cheap when its factor holds at most as many entries as the system (both
// triangles): the preconditioner then costs no more memory than the matrix. Its rows follow
// slivers and degenerate faces, which do not fill in: 0.10–0.22 of the system's entries on the
// shared buildings, refined sibenik's included (`prtsub bench SCENE --solve`).
constexpr double kCheapBlock = 1;
// When the block is dear: a share of stiff rows from which the whole system goes to CHOLMOD if
// its factor holds at most kCheapFill times the system's non-zeros (3× on conference; a 3-D
// scan's is 10×, armadillo's).
constexpr double kStiffShare = 0.01;
constexpr double kCheapFill = 6;

// The rows whose mass is under `share` of their scaled diagonal (the analytic mass's diagonal is
// half the lumped mass).
std::vector<Eigen::Index> stiff_rows(const FitSystem& sys, double share) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < sys.scale.size(); ++i)
    if (0.5 * sys.lumped[i] * sys.scale[i] * sys.scale[i] < share) rows.push_back(i);
  return rows;
}

}  // namespace

FitSystemSolver::FitSystemSolver(const FitSystem& system, const FitOptions& options) : system_(system), options_(options) {}
FitSystemSolver::~FitSystemSolver() = default;

// Singular, or too ill-conditioned to trust: CHOLMOD stops at a non-positive pivot, or the
// smallest pivot is below kMinRcond of the largest. (A threshold of 1e-12 let through systems
// that turned sample noise into errors of 2000% with the sampled mass and 2 samples per
// triangle; the analytic mass matrix, Jacobi-scaled, stays far above it even with 1e-4° slivers.)
// If it fails, add λ·D (D the lumped mass) with λ = 1e-9, 1e-6, 1e-3, 1: the smallest that holds.
void FitSystemSolver::analyze(FitStats& stats) {
  const Stopwatch clock;
  lower_ = system_.matrix.triangularView<Eigen::Lower>();
  cholesky_ = std::make_unique<Cholesky>();
  cholesky_->cholmod().print = 0;  // failures are ours to report, in one line
  cholesky_->analyzePattern(lower_);
  predicted_factor_entries_ = cholesky_->cholmod().lnz;
  stats.seconds_factor += clock.total();
}

void FitSystemSolver::factorize(FitStats& stats) {
  if (!cholesky_) analyze(stats);
  const Stopwatch clock;
  const Eigen::Index n = system_.matrix.rows();
  const SparseMatrixd& lower = lower_;
  const double kMinRcond = 1e-7;
  auto holds = [&]() { return cholesky_->info() == Eigen::Success && cholesky_->rcond() > kMinRcond; };
  cholesky_->factorize(lower);
  bool ok = holds();
  for (double lambda : {1e-9, 1e-6, 1e-3, 1.0}) {
    if (ok) break;
    SparseMatrixd m = lower;
    for (Eigen::Index i = 0; i < n; ++i) m.coeffRef(i, i) += lambda * system_.lumped[i] * system_.scale[i] * system_.scale[i];
    cholesky_->factorize(m);
    ok = holds();
    if (ok) stabilizer_ = lambda;
  }
  if (!ok) throw SolverError("fit: the least-squares system could not be factorised even when pulled towards the point samples");
  factor_entries_ = cholesky_->factor_entries();
  factored_ = true;
  stats.seconds_factor += clock.total();
}

RowMatrixXd FitSystemSolver::solve(const RowMatrixXd& prior, FitStats* stats_out) {
  FitStats stats = stats_out ? *stats_out : FitStats();
  Stopwatch clock;
  const FitSystem& sys = system_;
  const Eigen::Index n = sys.matrix.rows(), K = sys.rhs.cols();
  const std::vector<Eigen::Index>& slot = sys.slot;
  RowMatrixXd x = prior;
  const double vectors_bytes = 8.0 * static_cast<double>(n) * static_cast<double>(K);
  // Conjugate gradients first where the system is known to be well conditioned: the analytic
  // mass matrix, Jacobi-scaled, has eigenvalues in [1/2, 2] whatever the mesh. Started at the
  // prior, they need a few dozen passes over the matrix; a Cholesky factor of a 3-D mesh fills in.
  // The solver is chosen before any iteration is spent. Where the regulariser carries nearly all
  // of a row's diagonal (slivers beside large faces, degenerate faces), Jacobi-scaled CG crawls;
  // so CG solves those rows' block directly in each iteration (StiffBlock), its factor made once.
  // Only if that factor would outgrow the system (a stiff 3-D region) does the whole system's
  // symbolic analysis (reused by the factorisation) choose: CHOLMOD if its factor is small, Jacobi
  // CG (with the stall check as a last resort) if not.
  bool iterate = n > 0 && !factored_ && options_.solver != FitSolver::Cholmod && options_.mass == MassMatrix::Analytic;
  bool multigrid = options_.solver == FitSolver::Multigrid;
  std::vector<Eigen::Index> stiff = n > 0 ? stiff_rows(sys, options_.stiff_mass) : std::vector<Eigen::Index>();
  if (n > 0) stats.stiff_share = double(stiff.size()) / double(n);
  if (iterate && !multigrid && !stiff.empty() && !stiff_tried_) {
    stiff_tried_ = true;
    stats.seconds_solve += clock.lap();  // the set-up above (x's copy of the prior) is the solve's
    stiff_ = std::make_unique<StiffBlock>(sys.matrix, std::move(stiff));
    const bool cheap = double(stiff_->predicted_factor_entries()) <= kCheapBlock * double(sys.matrix.nonZeros());
    if (!cheap || !stiff_->factorise()) stiff_.reset();
    stats.seconds_factor += clock.lap();
  }
  if (stiff_) stats.stiff_rows = stiff_->rows().size(), stats.stiff_factor_entries = stiff_->predicted_factor_entries();
  if (iterate && options_.solver == FitSolver::Auto && !stiff_) {
    if (stats.stiff_share >= kStiffShare) {
      if (!cholesky_) analyze(stats);
      stats.predicted_factor_entries = size_t(predicted_factor_entries_);
      iterate = predicted_factor_entries_ > kCheapFill * double(sys.matrix.nonZeros());
    }
    clock.lap();
  }
  if (iterate) {
    RowMatrixXd y(n, K);
    for (size_t i = 0; i < slot.size(); ++i)
      if (slot[i] >= 0) y.row(slot[i]) = prior.row(static_cast<Eigen::Index>(i)) / sys.scale[slot[i]];
    BlockPreconditioner preconditioner;
    if (multigrid) {
      if (!multigrid_) {
        MultigridOptions mo;
        mo.threads = options_.threads;
        // In the scaled unknowns y = S⁻¹x, the constant and the linear functions, which the
        // regulariser does not penalise, are S⁻¹ times them.
        // (A system assembled for another solver has no positions: the constant alone.)
        const bool linear = sys.points.rows() == n;
        Eigen::MatrixXd near_null(n, linear ? 4 : 1);
        near_null.col(0).setOnes();
        if (linear) near_null.rightCols(3) = sys.points;
        near_null = sys.scale.cwiseInverse().asDiagonal() * near_null;
        multigrid_ = std::make_unique<Multigrid>(sys.matrix, mo, near_null);
        stats.seconds_factor += clock.lap();
      }
      stats.multigrid_levels = int(multigrid_->stats().unknowns.size());
      stats.multigrid_operator_complexity = multigrid_->stats().operator_complexity;
      const Multigrid& mg = *multigrid_;
      preconditioner = [&mg](const RowMatrixXd& r, RowMatrixXd& z) { mg.apply(r, z); };
    }
    const BlockCgOptions co{options_.cg_tolerance, options_.cg_max_iterations, options_.threads};
    const BlockCgResult cg = stiff_ && !multigrid ? block_conjugate_gradient(sys.matrix, sys.rhs, y, co, stiff_->inverse())
                                                  : block_conjugate_gradient(sys.matrix, sys.rhs, y, co, preconditioner);
    stats.cg_iterations = cg.iterations;
    if (cg.converged && y.allFinite()) {
      for (size_t i = 0; i < slot.size(); ++i)
        if (slot[i] >= 0) x.row(static_cast<Eigen::Index>(i)) = sys.scale[slot[i]] * y.row(slot[i]);
      stats.solver = multigrid ? "cg-multigrid" : "cg";
      stats.seconds_solve += clock.lap();
      double hierarchy = multigrid ? multigrid_->stats().bytes + 3 * vectors_bytes : 0.0;  // + Z and a cycle's two work arrays
      if (stiff_ && !multigrid)  // the block, its factor and M⁻¹R on its rows
        hierarchy += 12.0 * double(stiff_->block_nonzeros() + stiff_->predicted_factor_entries()) +
                     8.0 * double(stiff_->rows().size()) * double(K);
      stats.solve_memory_mib = (12.0 * static_cast<double>(sys.matrix.nonZeros()) + 6 * vectors_bytes + hierarchy) / (1024.0 * 1024.0);
      if (stats_out) *stats_out = stats;
      return x;
    }
    // Not a warning: a stiff system (slivers beside large faces) is CHOLMOD's job, and the
    // stats say which solver ran. CG's attempt counts as factorisation time.
    stats.seconds_factor += clock.lap();
  }
  if (n > 0) {
    if (!factored_) factorize(stats);
    clock.lap();
    stats.solver = "cholmod";
    stats.stabilizer = stabilizer_;
    stats.factor_nonzeros = factor_entries_;
    // The stabilised system (M + λ·S D S) y = S b + λ·S D prior, in the scaled unknowns y = x / S.
    Eigen::MatrixXd rhs = sys.rhs;
    if (stabilizer_ > 0)
      for (size_t i = 0; i < slot.size(); ++i)
        if (slot[i] >= 0) rhs.row(slot[i]) += stabilizer_ * sys.lumped[slot[i]] * sys.scale[slot[i]] * prior.row(static_cast<Eigen::Index>(i));
    const Eigen::MatrixXd sol = sys.scale.asDiagonal() * cholesky_->solve(rhs);
    if (!sol.allFinite()) throw SolverError("fit: the least-squares solve produced non-finite values");
    for (size_t i = 0; i < slot.size(); ++i)
      if (slot[i] >= 0) x.row(static_cast<Eigen::Index>(i)) = sol.row(slot[i]);
    stats.seconds_solve += clock.lap();
  }
  const double bytes = 12.0 * static_cast<double>(stats.system_nonzeros + size_t(n)) / 2 + 8.0 * static_cast<double>(stats.factor_nonzeros) +
                       3 * vectors_bytes;
  stats.solve_memory_mib = bytes / (1024.0 * 1024.0);
  if (stats_out) *stats_out = stats;
  return x;
}

namespace {

// Per vertex, the mean over the faces around it of a per-vertex quantity at their corners: the
// noise and bias estimates below are χ²-like with few degrees of freedom each, and the ring
// averages them while following how they change over the surface.
std::vector<double> ring_mean(const Mesh& mesh, const std::vector<double>& q) {
  std::vector<double> sum(q.size(), 0.0), count(q.size(), 0.0);
  for (const Triangle& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      sum[t[c]] += q[t[0]] + q[t[1]] + q[t[2]];
      count[t[c]] += 3;
    }
  for (size_t i = 0; i < q.size(); ++i) sum[i] = count[i] > 0 ? sum[i] / count[i] : q[i];
  return sum;
}

// The right-hand side's variance per vertex (summed over its K values): the moments' variances
// of the faces around it.
std::vector<double> rhs_variance(const Mesh& mesh, const FaceMoments& m) {
  std::vector<double> v(mesh.num_vertices(), 0.0);
  for (size_t f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) v[mesh.triangles[f][c]] += m.variance[3 * f + size_t(c)];
  return v;
}

// kProbes seeded ±1 columns scaled by the right-hand side's standard deviation: solved with the
// system, their squared solutions average to the fit's variance at each vertex (b's noise
// propagated through (A + αR)⁻¹, which a lumped mass would underestimate several times over).
constexpr int kProbes = 4;
void append_probes(FitSystem& sys, const std::vector<double>& var_b) {
  const Eigen::Index n = sys.rhs.rows(), K = sys.rhs.cols();
  sys.rhs.conservativeResize(n, K + kProbes);
  Rng rng(0x9b0be5ull, 0);
  for (size_t i = 0; i < sys.slot.size(); ++i) {
    if (sys.slot[i] < 0) continue;
    const Eigen::Index r = sys.slot[i];
    for (int k = 0; k < kProbes; ++k) sys.rhs(r, K + k) = sys.scale[r] * std::sqrt(var_b[i]) * ((rng.next() & 1) ? 1.0 : -1.0);
  }
}

// x = prior + s (x − prior) per vertex, s the share of the correction that minimises the
// expected squared error of the mix when the prior carries a bias β² and noise σp² and the fit
// noise σf²: s = (β² + σp²) / (β² + σp² + σf²), with β² = ‖x − prior‖² − σf² − σp² (at least 0).
double weigh_by_noise(const Mesh& mesh, const std::vector<double>& var_f, const std::vector<double>& prior_variance,
                      const RowMatrixXd& prior, RowMatrixXd& x) {
  const size_t V = mesh.num_vertices();
  std::vector<double> d2(V);
  for (size_t i = 0; i < V; ++i) d2[i] = (x.row(static_cast<Eigen::Index>(i)) - prior.row(static_cast<Eigen::Index>(i))).squaredNorm();
  const std::vector<double> vf = ring_mean(mesh, var_f), vp = ring_mean(mesh, prior_variance), dd = ring_mean(mesh, d2);
  double kept = 0;
  for (size_t i = 0; i < V; ++i) {
    double share = 1;
    if (!std::isfinite(vp[i])) share = 1;       // the prior's noise is unknown: keep the fit
    else if (!std::isfinite(vf[i])) share = 0;  // the fit's is: keep the prior
    else {
      const double bias2 = std::max(0.0, dd[i] - vf[i] - vp[i]);
      const double denominator = bias2 + vp[i] + vf[i];
      share = denominator > 0 ? (bias2 + vp[i]) / denominator : 1;
    }
    const auto r = static_cast<Eigen::Index>(i);
    x.row(r) = prior.row(r) + share * (x.row(r) - prior.row(r));
    kept += share;
  }
  return V ? kept / static_cast<double>(V) : 1;
}

// Constant: clamps each vertex's DC coefficient at 0 (a constant light sees nothing else, and
// the other coefficients keep the fit). Directions: first pulls each vertex towards its prior,
// x = prior + s (x − prior) with the largest s in [0, 1], until its transfer function
// T(ω) = Σ x_k y_k(ω) is at least min(0, min T_prior) at a fixed set of directions (linear in s).
// Interpolation across a triangle mixes vertex functions convexly, so both bounds hold there.
size_t keep_non_negative(const RowMatrixXd& prior, RowMatrixXd& x, NonNegative mode, int threads) {
  if (mode == NonNegative::Off) return 0;
  // RGB transfer (three blocks of N², docs/sh_convention.md "Colour"): every channel's bound.
  const int channels = std::max(transfer_channels(x.cols()), 1);
  const Eigen::Index K = x.cols() / channels;
  const int order = static_cast<int>(std::lround(std::sqrt(double(K))));
  constexpr int kDirections = 128;
  RowMatrixXd Y(kDirections, K);  // SH at a Fibonacci sphere
  const bool directions = mode == NonNegative::Directions && order * order == K;
  for (int d = 0; d < kDirections && directions; ++d) {
    const double z = 1 - (2.0 * d + 1) / kDirections, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2.399963229728653 * d;
    sh_eval(order, r * std::cos(phi), r * std::sin(phi), z, Y.row(d).data());
  }
  std::vector<char> limited(static_cast<size_t>(x.rows()), 0);
  parallel_range(x.rows(), threads, Eigen::Index(256), [&](const tbb::blocked_range<Eigen::Index>& range) {
    for (Eigen::Index i = range.begin(); i < range.end(); ++i) {
      if (directions) {
        double share = 1;
        for (int c = 0; c < channels; ++c) {
          const Eigen::VectorXd tp = Y * prior.row(i).segment(c * K, K).transpose(), tx = Y * x.row(i).segment(c * K, K).transpose();
          const double floor = std::min(0.0, tp.minCoeff());
          for (int d = 0; d < kDirections; ++d)
            if (tx[d] < floor && tp[d] > tx[d]) share = std::min(share, (tp[d] - floor) / (tp[d] - tx[d]));
        }
        if (share < 1) x.row(i) = prior.row(i) + std::max(share, 0.0) * (x.row(i) - prior.row(i)), limited[size_t(i)] = 1;
      }
      for (int c = 0; c < channels; ++c)
        if (x(i, c * K) < 0) x(i, c * K) = 0, limited[size_t(i)] = 1;
    }
  });
  return static_cast<size_t>(std::count(limited.begin(), limited.end(), 1));
}

}  // namespace

namespace {

// With the pilot's allocation only the corners of sampled faces can be unknowns: a vertex whose
// faces are all left to interpolation is fitted to its prior's own interpolant, which is its
// prior. An unknown's row reaches the faces around it and, through the edge regulariser, the
// faces across their edges; so the system assembled over the faces with a corner within one
// ring (over positions) of a sampled face's corners is the whole mesh's system, row for row.
// On a dense mesh that region is a few percent of the faces, and assembling there keeps the
// fit's time and memory with the sampled faces, not the mesh (armadillo refined to 1.5M
// triangles: BENCHMARKS.md, "The fit on the sampled region"). Only the degeneracy floors,
// relative to the mean face, and the order sums are taken in differ from a whole-mesh assembly.
struct FitRegion {
  Mesh mesh;  // no faces: the region is most of the mesh, fit the whole
  SurfaceSamples samples;
  FaceMoments moments;
  RowMatrixXd prior;
  std::vector<uint32_t> vertex;  // the region's vertex → the mesh's, ascending (append_probes' order is kept)
};

FitRegion fit_region(const Mesh& mesh, const SurfaceSamples& s, const FaceMoments& m, const RowMatrixXd& prior) {
  FitRegion r;
  const size_t F = mesh.num_faces(), V = mesh.num_vertices(), P = static_cast<size_t>(mesh.positions.rows());
  // Shapes that do not match take the whole-mesh path, whose assembly reports them.
  if (s.interpolated.size() != F || F == 0 || s.begin.size() != F + 1 || static_cast<size_t>(m.rows.rows()) != 3 * F ||
      static_cast<size_t>(prior.rows()) != V || prior.cols() != m.rows.cols() ||
      std::any_of(s.face.begin(), s.face.end(), [F](uint32_t f) { return f >= F; }))
    return r;
  const std::vector<uint32_t>& vp = mesh.vertex_position;
  std::vector<char> seed(P, 0), ring(P, 0);
  for (size_t f = 0; f < F; ++f)
    if (face_has_samples(s, f))
      for (uint32_t v : mesh.triangles[f]) seed[vp[v]] = 1;
  for (const Triangle& t : mesh.triangles)
    if (seed[vp[t[0]]] || seed[vp[t[1]]] || seed[vp[t[2]]])
      for (uint32_t v : t) ring[vp[v]] = 1;
  std::vector<uint32_t> faces;
  for (uint32_t f = 0; f < F; ++f) {
    const Triangle& t = mesh.triangles[f];
    if (ring[vp[t[0]]] || ring[vp[t[1]]] || ring[vp[t[2]]]) faces.push_back(f);
  }
  if (faces.empty() || 2 * faces.size() > F) return r;
  // Vertices and positions numbered in the mesh's order.
  std::vector<int64_t> vslot(V, -1), pslot(P, -1);
  for (uint32_t f : faces)
    for (uint32_t v : mesh.triangles[f]) vslot[v] = 0, pslot[vp[v]] = 0;
  uint32_t nv = 0, np = 0;
  for (size_t v = 0; v < V; ++v)
    if (vslot[v] >= 0) vslot[v] = nv++, r.vertex.push_back(static_cast<uint32_t>(v));
  for (size_t p = 0; p < P; ++p)
    if (pslot[p] >= 0) pslot[p] = np++;
  Mesh& sub = r.mesh;
  sub.positions.resize(np, 3);
  for (size_t p = 0; p < P; ++p)
    if (pslot[p] >= 0) sub.positions.row(pslot[p]) = mesh.positions.row(static_cast<Eigen::Index>(p));
  const bool normals = static_cast<size_t>(mesh.normals.rows()) == V;
  if (normals) sub.normals.resize(nv, 3);
  r.prior.resize(nv, prior.cols());
  sub.vertex_position.resize(nv);
  for (uint32_t j = 0; j < nv; ++j) {
    const uint32_t v = r.vertex[j];
    sub.vertex_position[j] = static_cast<uint32_t>(pslot[vp[v]]);
    if (normals) sub.normals.row(j) = mesh.normals.row(v);
    r.prior.row(j) = prior.row(v);
  }
  sub.triangles.reserve(faces.size());
  for (uint32_t f : faces) {
    const Triangle& t = mesh.triangles[f];
    sub.triangles.push_back({static_cast<uint32_t>(vslot[t[0]]), static_cast<uint32_t>(vslot[t[1]]), static_cast<uint32_t>(vslot[t[2]])});
  }
  sub.crease_angle_deg = mesh.crease_angle_deg;
  // Every sample lies on a sampled face, and every sampled face is in the region: the samples
  // keep their order, and each face its range.
  r.samples = s;
  std::vector<uint32_t> fslot(F, 0);
  for (uint32_t k = 0; k < faces.size(); ++k) fslot[faces[k]] = k;
  for (uint32_t& f : r.samples.face) f = fslot[f];
  r.samples.begin.resize(faces.size() + 1);
  r.samples.interpolated.resize(faces.size());
  for (size_t k = 0; k < faces.size(); ++k) r.samples.begin[k] = s.begin[faces[k]], r.samples.interpolated[k] = s.interpolated[faces[k]];
  r.samples.begin[faces.size()] = s.begin[faces.back() + 1];
  if (r.samples.begin.front() != 0 || r.samples.begin.back() != s.size()) throw InputError("fit: samples outside the sampled faces");
  const Eigen::Index K = m.rows.cols();
  r.moments.rows = RowMatrixXd::Zero(static_cast<Eigen::Index>(3 * faces.size()), K);  // (only sampled faces' rows are read)
  const bool variance = m.variance.size() == 3 * F;
  if (variance) r.moments.variance.assign(3 * faces.size(), 0.0);
  for (size_t k = 0; k < faces.size(); ++k)
    for (size_t c = 0; c < 3 && face_has_samples(s, faces[k]); ++c) {
      r.moments.rows.row(static_cast<Eigen::Index>(3 * k + c)) = m.rows.row(static_cast<Eigen::Index>(3 * size_t(faces[k]) + c));
      if (variance) r.moments.variance[3 * k + c] = m.variance[3 * size_t(faces[k]) + c];
    }
  return r;
}

}  // namespace

namespace {

// The prior corrected by the known part's exact projection: point values + P(w·t_u) − w·t_u(n),
// w each vertex's open share (t_u's curvature in n shows in t as far as the point is open; an
// enclosed region's t is near zero and near linear). The fit then runs as ever around it: a
// vertex no sampled face touches keeps the corrected value, faces left to interpolation take its
// interpolant as their data, and the regulariser sees the whole signal.
RowMatrixXd corrected_prior(const Mesh& mesh, const RowMatrixXd& prior, const FitOptions& o, FitStats& stats) {
  const Eigen::Index K = prior.cols(), N2 = sh_count(o.unshadowed_order);
  if (K % N2 != 0 || K / N2 > 3 || prior.rows() != static_cast<Eigen::Index>(mesh.num_vertices()))
    throw InputError("fit: the prior is not shadowed transfer of order " + std::to_string(o.unshadowed_order) + " at every vertex");
  const Stopwatch clock;
  UnshadowedProjectionOptions po;
  po.threads = o.threads;
  UnshadowedProjectionStats ps;
  const std::vector<double> open = open_share(prior);
  RowMatrixXd correction = unshadowed_projection(mesh, o.unshadowed_order, po, &ps, &open);
  const RowMatrixXd at_vertices = unshadowed_at(mesh.normals, o.unshadowed_order);
  for (Eigen::Index i = 0; i < correction.rows(); ++i) correction.row(i) -= open[static_cast<size_t>(i)] * at_vertices.row(i);
  stats.unshadowed_iterations = ps.iterations, stats.seconds_unshadowed = clock.total();
  return prior + correction.replicate(1, K / N2);
}

}  // namespace

RowMatrixXd fit_prior(const Mesh& mesh, const RowMatrixXd& prior, const FitOptions& o, FitStats* stats) {
  FitStats st;
  RowMatrixXd p = o.method == FitMethod::LeastSquares && o.unshadowed_order > 0 ? corrected_prior(mesh, prior, o, st) : prior;
  if (stats) stats->unshadowed_iterations = st.unshadowed_iterations, stats->seconds_unshadowed = st.seconds_unshadowed;
  return p;
}

RowMatrixXd fit_vertex_values(const Mesh& mesh, const SurfaceSamples& s, const FaceMoments& moments,
                              const RowMatrixXd& given_prior, const FitOptions& o, FitStats* stats_out,
                              const std::vector<double>* prior_variance) {
  // The least-squares path checks its inputs in assemble_fit_system; the others here.
  if (o.method != FitMethod::LeastSquares) check_fit_inputs(mesh, s, moments, given_prior, o);
  FitStats stats;
  const bool known = o.method == FitMethod::LeastSquares && o.unshadowed_order > 0;
  const RowMatrixXd corrected = known ? corrected_prior(mesh, given_prior, o, stats) : RowMatrixXd();
  const RowMatrixXd& prior = known ? corrected : given_prior;
  stats.unknowns = mesh.num_vertices();
  RowMatrixXd x;
  if (o.method == FitMethod::Point) {
    x = prior;
  } else if (o.method == FitMethod::Average) {
    const Stopwatch clock;
    // In the mesh's own order (rank = vertex index).
    std::vector<uint32_t> identity(mesh.num_vertices()), faces(mesh.num_faces());
    for (uint32_t i = 0; i < identity.size(); ++i) identity[i] = i;
    for (uint32_t f = 0; f < faces.size(); ++f) faces[f] = f;
    const FaceSums sums = sum_faces(mesh, s, all_face_geometry(mesh, o.threads), moments, prior, identity, faces, o);
    const Eigen::VectorXd& lumped = o.mass == MassMatrix::Analytic ? sums.lumped_analytic : sums.lumped_sampled;
    const double typical = lumped.sum() / static_cast<double>(std::max<size_t>(mesh.num_vertices(), 1));
    std::vector<char> free(mesh.num_vertices());
    for (size_t i = 0; i < free.size(); ++i) {
      free[i] = lumped[static_cast<Eigen::Index>(i)] > 1e-12 * typical && sums.support[static_cast<Eigen::Index>(i)] > 1e-12 * typical;
      stats.unsupported += !free[i];
    }
    x = average_values(sums, free, prior);
    stats.seconds_assemble = clock.total();
  } else if (s.size() == 0) {
    // No sample (the pilot's screen stopped it, or it found no face): no vertex has a row of its
    // own, and each keeps its (corrected) prior. Assembling the empty system would still sum over
    // every face: a second on a 1.5M-triangle bake.
    check_fit_inputs(mesh, s, moments, prior, o);
    x = prior;
    stats.unsupported = mesh.num_vertices();
  } else {
    // The system on the sampled faces' region (fit_region), or on the whole mesh. The assembly
    // checks what it is given; the region's caller checks the whole (its prior rows outside the
    // region become values too).
    const FitRegion region = fit_region(mesh, s, moments, prior);
    const bool part = region.mesh.num_faces() > 0;
    if (part) check_fit_inputs(mesh, s, moments, prior, o);
    const Mesh& rm = part ? region.mesh : mesh;
    const SurfaceSamples& rs = part ? region.samples : s;
    const FaceMoments& rmo = part ? region.moments : moments;
    const RowMatrixXd& rp = part ? region.prior : prior;
    FitSystem system = assemble_fit_system(rm, rs, rmo, rp, o, &stats);
    const bool weigh = o.weigh_by_noise && prior_variance && moments.variance.size() == 3 * mesh.num_faces() &&
                       prior_variance->size() == mesh.num_vertices();
    const Eigen::Index K = prior.cols();
    if (weigh) append_probes(system, rhs_variance(rm, rmo));
    RowMatrixXd start = rp;
    if (weigh) start.conservativeResize(Eigen::NoChange, K + kProbes), start.rightCols(kProbes).setZero();
    FitSystemSolver solver(system, o);
    RowMatrixXd xr = solver.solve(start, &stats);
    std::vector<double> var_f(weigh ? mesh.num_vertices() : 0, INFINITY);  // the fit's variance; fixed vertices: unknown
    for (size_t j = 0; j < rm.num_vertices() && weigh; ++j)
      if (system.slot[j] >= 0)
        var_f[part ? region.vertex[j] : j] = xr.row(static_cast<Eigen::Index>(j)).rightCols(kProbes).squaredNorm() / kProbes;
    if (part) {
      x = prior;
      for (size_t j = 0; j < rm.num_vertices(); ++j) x.row(region.vertex[j]) = xr.row(static_cast<Eigen::Index>(j)).leftCols(K);
      stats.unknowns = mesh.num_vertices();
      stats.unsupported += mesh.num_vertices() - rm.num_vertices();
    } else {
      x = std::move(xr);
      if (weigh) x.conservativeResize(Eigen::NoChange, K);
    }
    if (weigh) stats.kept_correction = weigh_by_noise(mesh, var_f, *prior_variance, prior, x);
    stats.limited_vertices = keep_non_negative(prior, x, o.non_negative, o.threads);
    if (o.mass == MassMatrix::Sampled && static_cast<double>(s.size()) < 8.0 * static_cast<double>(mesh.num_faces()))
      stats.warning = "fit: the sampled mass matrix with under 8 samples per triangle extrapolates vertices that samples barely "
                      "see; errors can be far above point sampling (docs/fit.md). Prefer the analytic mass matrix.";
    if (stats.stabilizer > 0) {
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "fit: the least-squares system is singular to working precision (alpha %g, %s mass matrix); "
                    "stabilised towards the point samples with lambda %g",
                    o.alpha, mass_matrix_name(o.mass), stats.stabilizer);
      stats.warning += (stats.warning.empty() ? "" : " ") + std::string(buf);
    }
  }
  if (stats_out) *stats_out = stats;
  return x;
}

}  // namespace prtsub
