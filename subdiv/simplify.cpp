// Budgeted simplification by half-edge collapses on OpenMesh's Decimater.
//
// The mesh goes into an OpenMesh TriMesh over its welded positions; each face keeps its render
// corners (and source face) beside it, so creases and UV seams survive: a position edge whose
// two faces do not share render vertices is a feature, and OpenMesh's own rule lets a feature
// vertex collapse only along a feature edge. Faces OpenMesh cannot take (non-manifold edges or
// vertices, repeated corners) stay out of it, unchanged, with their vertices locked. A crease's
// end and a crease meeting a boundary are locked too (where they would slide is not one line).
// A corner (three or more creases) may collapse along one of its creases: the faces beyond the
// other creases keep their own render vertex, which moves with the position to p1; its value
// is estimated by those faces' linear extension to p1 for ranking, and the caller traces it
// again there (SimplifyStats::moved). After each collapse the feature flags around v1 are
// recomputed, since a collapse can merge or end a crease.
//
// One non-binary module ranks a collapse of v0 into v1 (Vanhoey et al. 2012, section 4.1):
//   E_signal = Σ_t area(t) · ‖L(p0) − L_t(p0)‖² over the faces t the collapse changes, where
//              L_t(p0) extends t's linear interpolant to p0 with its constant gradient (their
//              equation 4: p0 projected onto t's plane, barycentrics allowed outside t), and
//              L(p0) is v0's own value on t's side of any crease;
//   E_geom   = Σ_f area(f) · ((p1 − p0) · n_f)² over the faces around v0 before the collapse:
//              the memoryless quadric (Lindstrom and Turk), evaluated where v0 goes.
// Where the values are noisy estimates (traced transfer), d² above is on average the signal's
// change plus what the corners' noise alone gives, v0 + w1²·v1 + wa²·va + wb²·vb for the
// extension's weights w of t's corners: that is subtracted (the sum over faces clamped at
// zero), so that flat patches of noise are not kept for their noise (mori_knob at 10%: 4.335%
// to 4.192%).
// Both are memoryless, as the paper combines them. The signal is SH in one global frame, so the
// distance of the paper's equation 5 is the coefficient distance. Priority:
//   E_signal / value_scale² + geometry_weight · E_geom / diagonal²   (Geometry: E_geom alone).
// The same module refuses collapses that flip a face (its normal turns by 90° or more, or comes
// to face against one of its corners' render normals when it did not before), make a
// face below the minimum angle (unless the faces replaced were worse) or without area, put v1
// off the plane of one of v0's faces by more than the surface tolerance, or move a boundary or
// feature line by more than its tolerance (the distance of v0 from the line that replaces its
// two line edges). Where the budget is out of reach, the surface tolerance doubles (up to its
// maximum), and that relaxed run is kept only if it gets at least halfway from where the strict
// run stopped.
//
// A collapse removes two faces, or one on a boundary, so the Decimater is run to budget + 1;
// if it stops there, one boundary collapse (the best legal one) ends exactly on the budget; a
// closed surface has no such collapse and ends one below, with a warning.
#include "prtsub/subdiv/simplify.h"

// OpenMesh's property containers trip g++ 12's maybe-uninitialized when instantiated here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModBaseT.hh>
#include <OpenMesh/Tools/Decimater/Observer.hh>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/refine.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {

SimplifyMetric parse_simplify_metric(const std::string& name) {
  if (name == "transfer") return SimplifyMetric::Transfer;
  if (name == "geometry") return SimplifyMetric::Geometry;
  throw InputError("unknown simplification metric '" + name + "' (expected transfer or geometry)");
}

const char* simplify_metric_name(SimplifyMetric m) { return m == SimplifyMetric::Geometry ? "geometry" : "transfer"; }

namespace {

struct Traits : OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using OMesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;

inline Eigen::Vector3d vec(const OMesh::Point& p) { return {p[0], p[1], p[2]}; }

// A setting as a user typed it (5, 0.5), not std::to_string's six decimals.
std::string short_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

// Everything the module reads: the input, and each OpenMesh face's corners as our mesh has them.
struct State {
  RowMatrixXd* values = nullptr;  // a corner collapse's moved render vertices get new estimates
  const std::vector<double>* variance = nullptr;  // per render vertex: its value's noise (none: taken as exact)
  const RowMatrixX3d* normals = nullptr;  // per render vertex (none: the guard that reads them is off)
  SimplifyOptions options;
  double diagonal = 1, cos_min_angle = 1, surface_tolerance = 0;
  std::vector<std::array<uint32_t, 3>> corner_pos, corner_render;  // per OpenMesh face, our corner order
  std::vector<uint32_t> source;                                     // per OpenMesh face
  std::vector<char> feature;                                        // per OpenMesh edge
  std::vector<uint32_t> render_pos;  // per input render vertex: its position now (a corner collapse moves some)
  std::vector<char> moved;           // per input render vertex: a corner collapse moved it
  size_t corner_collapses = 0;
  size_t refused_flip = 0, refused_angle = 0, refused_line = 0, refused_side = 0, refused_surface = 0;  // evaluations refused

  // Render vertex r's noise; an unknown one (NaN) counts as none.
  double var(uint32_t r) const {
    if (!variance) return 0;
    const double v = (*variance)[r];
    return std::isfinite(v) && v > 0 ? v : 0;
  }
  uint32_t render_at(FaceHandle f, VertexHandle v) const {
    const auto& p = corner_pos[size_t(f.idx())];
    for (int k = 0; k < 3; ++k)
      if (p[k] == uint32_t(v.idx())) return corner_render[size_t(f.idx())][k];
    return UINT32_MAX;
  }
};

// The largest corner-angle cosine of (a, b, c): its smallest angle's cosine (1 without area).
double max_cosine(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d p[3] = {a, b, c};
  double worst = -1;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d u = p[(k + 1) % 3] - p[k], w = p[(k + 2) % 3] - p[k];
    const double n = u.norm() * w.norm();
    if (!(n > 0)) return 1;
    worst = std::max(worst, u.dot(w) / n);
  }
  return worst;
}

// Distance of p from the segment [a, b].
double segment_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double t = d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + t * d - p).norm();
}

// Whether edge e is a feature: its two faces see different render vertices at an end.
bool is_feature(const OMesh& m, const State& s, OMesh::EdgeHandle e) {
  const HalfedgeHandle h = m.halfedge_handle(e, 0);
  const FaceHandle f = m.face_handle(h), g = m.face_handle(m.opposite_halfedge_handle(h));
  if (!f.is_valid() || !g.is_valid()) return false;
  const VertexHandle a = m.from_vertex_handle(h), b = m.to_vertex_handle(h);
  return s.render_at(f, a) != s.render_at(g, a) || s.render_at(f, b) != s.render_at(g, b);
}

// Why a vertex cannot move: a feature's end, or a feature meeting a boundary (where it would
// slide is not a line); with corners locked, three or more features meeting too.
bool locks(const OMesh& m, const State& s, VertexHandle v, int features) {
  return features == 1 || (features > 0 && m.is_boundary(v)) || (features > 2 && !s.options.collapse_corners);
}

// v's edges' feature flags and v's own, after a collapse changed its neighbourhood (a vertex
// locked once stays locked).
void update_features(OMesh& m, State& s, VertexHandle v) {
  int n = 0;
  for (OMesh::VertexEdgeIter e = m.ve_iter(v); e.is_valid(); ++e) {
    const bool f = is_feature(m, s, *e);
    s.feature[size_t(e->idx())] = f;
    m.status(*e).set_feature(f);
    n += f;
  }
  m.status(v).set_feature(n > 0);
  if (locks(m, s, v, n)) m.status(v).set_locked(true);
}

class ModTransfer : public OpenMesh::Decimater::ModBaseT<OMesh> {
 public:
  typedef ModTransfer Self;
  typedef OpenMesh::Decimater::ModHandleT<Self> Handle;
  typedef OpenMesh::Decimater::ModBaseT<OMesh> Base;
  typedef Base::CollapseInfo CollapseInfo;
  DECIMATER_MODNAME(PrtsubTransfer)

  explicit ModTransfer(OMesh& mesh) : Base(mesh, false) {}
  static float refuse(size_t& count) {
    ++count;
    return float(ILLEGAL_COLLAPSE);
  }
  void set_state(State* s) { s_ = s; }

  // Whether a face of normal n (any length) faces against the normal of one of its corners.
  bool faces_away(const Eigen::Vector3d& n, uint32_t a, uint32_t b, uint32_t c) const {
    if (!s_->normals) return false;
    const RowMatrixX3d& N = *s_->normals;
    return !(n.dot(N.row(a).transpose()) > 0 && n.dot(N.row(b).transpose()) > 0 && n.dot(N.row(c).transpose()) > 0);
  }

  float collapse_priority(const CollapseInfo& ci) override {
    worst_for_ = HalfedgeHandle();
    if (!sides(ci)) return refuse(s_->refused_side);
    const OMesh& m = Base::mesh();
    const Eigen::Vector3d p0 = vec(ci.p0), p1 = vec(ci.p1);
    const Eigen::Index K = s_->values->cols();
    if (moves_) estimate_moved(ci);
    double e_geom = 0, e_signal = 0;
    for (const auto& [f, r1] : changed_) {
      const auto& pos = s_->corner_pos[size_t(f.idx())];
      const auto& ren = s_->corner_render[size_t(f.idx())];
      int k0 = 0;
      while (pos[k0] != uint32_t(ci.v0.idx())) ++k0;
      const int ka = (k0 + 1) % 3, kb = (k0 + 2) % 3;
      const Eigen::Vector3d pa = vec(m.point(VertexHandle(int(pos[ka])))), pb = vec(m.point(VertexHandle(int(pos[kb]))));
      const Eigen::Vector3d n0 = (pa - p0).cross(pb - p0), n1 = (pa - p1).cross(pb - p1);
      if (!(n0.dot(n1) > 0)) return refuse(s_->refused_flip);  // flipped, or no area left
      // Nor may it face against one of its corners' normals (unless it did before): a small face
      // can turn far within the surface tolerance, and a corner's moved render vertex or v1's
      // render vertex of its side may bring a normal it never had (mori_knob: 24 such faces).
      if (faces_away(n1, r1, ren[ka], ren[kb]) && !faces_away(n0, ren[k0], ren[ka], ren[kb])) return refuse(s_->refused_flip);
      // Below the minimum angle only where the faces it replaces were already worse (a needle of
      // the input may be collapsed into something better, never into something worse).
      if (const double c = max_cosine(p1, pa, pb); c > s_->cos_min_angle && c > worst_before(ci)) return refuse(s_->refused_angle);
      const double area1 = 0.5 * n1.norm();
      if (K > 0) {
        // L_t(p0): t's interpolant extended with its constant gradient (least-squares barycentrics).
        Eigen::Matrix<double, 3, 2> J;
        J.col(0) = pa - p1, J.col(1) = pb - p1;
        const Eigen::Vector2d c = (J.transpose() * J).ldlt().solve(J.transpose() * (p0 - p1));
        const double* l1 = r1 == ren[k0] ? moved_value(r1) : s_->values->row(r1).data();
        const double* la = s_->values->row(ren[ka]).data();
        const double* lb = s_->values->row(ren[kb]).data();
        const double* l0 = s_->values->row(ren[k0]).data();
        double d2 = 0;
        for (Eigen::Index i = 0; i < K; ++i) {
          const double d = l0[i] - (l1[i] + c[0] * (la[i] - l1[i]) + c[1] * (lb[i] - l1[i]));
          d2 += d * d;
        }
        // What the corners' noise alone would give d² on average: subtracted, so that a collapse
        // is ranked by the signal's change, not by how noisy its corners happen to be.
        const double w1 = 1 - c[0] - c[1];
        d2 -= (s_->var(ren[k0]) + w1 * w1 * s_->var(r1) + c[0] * c[0] * s_->var(ren[ka]) + c[1] * c[1] * s_->var(ren[kb]));
        e_signal += area1 * d2;
      }
    }
    for (OMesh::ConstVertexFaceIter f = m.cvf_iter(ci.v0); f.is_valid(); ++f) {
      const Eigen::Vector3d n = vec(m.calc_face_normal(*f));
      const double area = face_area(*f);
      if (!(n.norm() > 0)) continue;
      const double d = (p1 - p0).dot(n.normalized());
      // v1 lies too far off the plane of a face v0 had: the collapse would move the surface by
      // more than the current tolerance (sibenik's last collapses, without it, tripled its error).
      if (std::abs(d) > s_->surface_tolerance) return refuse(s_->refused_surface);
      e_geom += area * d * d;
    }
    if (!lines_ok(ci)) return refuse(s_->refused_line);
    const double d2 = s_->diagonal * s_->diagonal;
    const double scale2 = s_->options.value_scale * s_->options.value_scale;
    e_signal = std::max(e_signal, 0.0);
    const double e = s_->options.metric == SimplifyMetric::Geometry || K == 0
                         ? e_geom / d2
                         : e_signal / scale2 + s_->options.geometry_weight * e_geom / d2;
    return float(std::min(e, 1e30));
  }

  // The collapse is about to happen: the changed faces' corners move from v0 to v1 (on their
  // side of a crease), before OpenMesh forgets which faces those were.
  void preprocess_collapse(const CollapseInfo& ci) override {
    if (!sides(ci)) return;  // cannot happen for a collapse this module allowed
    s_->corner_collapses += moves_;
    if (moves_) {
      estimate_moved(ci);
      for (size_t i = 0; i < moved_.size(); ++i) s_->values->row(moved_[i]) = moved_values_.row(Eigen::Index(i));
    }
    for (const auto& [f, r1] : changed_) {
      auto& pos = s_->corner_pos[size_t(f.idx())];
      auto& ren = s_->corner_render[size_t(f.idx())];
      for (int k = 0; k < 3; ++k) {
        if (pos[k] != uint32_t(ci.v0.idx())) continue;
        if (ren[k] == r1) s_->render_pos[r1] = uint32_t(ci.v1.idx()), s_->moved[r1] = 1;  // a corner's side, moved
        pos[k] = uint32_t(ci.v1.idx()), ren[k] = r1;
      }
    }
  }

  // The collapse is done: edges around v1 merged where faces went, and a corner's creases now
  // meet at v1, so which edges are features, and which vertices lie on them, is looked at again.
  void postprocess_collapse(const CollapseInfo& ci) override {
    OMesh& m = Base::mesh();
    update_features(m, *s_, ci.v1);
    for (OMesh::VertexVertexIter w = m.vv_iter(ci.v1); w.is_valid(); ++w) update_features(m, *s_, *w);
  }

 private:
  double face_area(FaceHandle f) {
    const auto& p = s_->corner_pos[size_t(f.idx())];
    const OMesh& m = Base::mesh();
    return triangle_area(vec(m.point(VertexHandle(int(p[0])))), vec(m.point(VertexHandle(int(p[1])))),
                         vec(m.point(VertexHandle(int(p[2])))));
  }

  // The smallest angle's cosine over the faces around v0 (those the collapse changes or removes).
  double worst_before(const CollapseInfo& ci) {
    if (worst_for_ == ci.v0v1) return worst_;
    const OMesh& m = Base::mesh();
    worst_ = -1, worst_for_ = ci.v0v1;
    for (OMesh::ConstVertexFaceIter f = m.cvf_iter(ci.v0); f.is_valid(); ++f) {
      const auto& p = s_->corner_pos[size_t(f->idx())];
      worst_ = std::max(worst_, max_cosine(vec(m.point(VertexHandle(int(p[0])))), vec(m.point(VertexHandle(int(p[1])))),
                                           vec(m.point(VertexHandle(int(p[2]))))));
    }
    return worst_;
  }

  // Fills changed_ with the faces around v0 other than fl and fr, each with the render vertex of
  // v1 it will use: the one of fl or fr, whichever it reaches around v0 without crossing a
  // feature edge. False when a face reaches neither (a feature the collapse would break).
  bool sides(const CollapseInfo& ci) {
    const OMesh& m = Base::mesh();
    changed_.clear();
    ring_.clear();
    for (OMesh::ConstVertexFaceIter f = m.cvf_iter(ci.v0); f.is_valid(); ++f) ring_.push_back({*f, -1});
    const FaceHandle start[2] = {ci.fl, ci.fr};
    uint32_t render[2] = {UINT32_MAX, UINT32_MAX};
    for (int side = 0; side < 2; ++side) {
      if (!start[side].is_valid()) continue;
      render[side] = s_->render_at(start[side], ci.v1);
      // Flood over faces around v0 that share a non-feature edge (v0, x).
      stack_.assign(1, start[side]);
      for (auto& [f, label] : ring_)
        if (f == start[side] && label < 0) label = side;
      while (!stack_.empty()) {
        const FaceHandle f = stack_.back();
        stack_.pop_back();
        for (OMesh::ConstFaceHalfedgeIter h = m.cfh_iter(f); h.is_valid(); ++h) {
          const VertexHandle a = m.from_vertex_handle(*h), b = m.to_vertex_handle(*h);
          if (a != ci.v0 && b != ci.v0) continue;
          if (s_->feature[size_t(m.edge_handle(*h).idx())] || m.is_boundary(m.edge_handle(*h))) continue;
          const FaceHandle g = m.face_handle(m.opposite_halfedge_handle(*h));
          for (auto& [rf, label] : ring_)
            if (rf == g && label < 0) label = side, stack_.push_back(g);
        }
      }
    }
    // A face neither side reaches lies beyond another crease at a corner: it keeps v0's render
    // vertex of its side, which moves to v1 (unless a reached face uses it too).
    moves_ = false;
    for (const auto& [f, label] : ring_) {
      if (f == ci.fl || f == ci.fr) continue;
      if (label >= 0 && render[label] == UINT32_MAX) return false;
      if (label < 0) {
        if (!s_->options.collapse_corners) return false;
        const uint32_t own = s_->render_at(f, ci.v0);
        for (const auto& [g, other] : ring_)
          if (other >= 0 && s_->render_at(g, ci.v0) == own) return false;
        changed_.push_back({f, own});
        moves_ = true;
        continue;
      }
      changed_.push_back({f, render[label]});
    }
    return true;
  }

  // A corner's side that moves to v1 keeps its render vertex, whose value is then expected to be
  // what that side's faces extend to at p1 (their constant gradients, area-weighted), as the
  // caller traces it there: a linear signal's faces are then unchanged.
  void estimate_moved(const CollapseInfo& ci) {
    const OMesh& m = Base::mesh();
    const Eigen::Index K = s_->values->cols();
    moved_.clear();
    moved_values_.setZero(0, K);
    std::vector<double> weight;
    const Eigen::Vector3d p0 = vec(ci.p0), p1 = vec(ci.p1);
    for (const auto& [f, r1] : changed_) {
      const auto& pos = s_->corner_pos[size_t(f.idx())];
      const auto& ren = s_->corner_render[size_t(f.idx())];
      int k0 = 0;
      while (pos[k0] != uint32_t(ci.v0.idx())) ++k0;
      if (ren[k0] != r1) continue;
      size_t i = 0;
      while (i < moved_.size() && moved_[i] != r1) ++i;
      if (i == moved_.size()) {
        moved_.push_back(r1), weight.push_back(0);
        moved_values_.conservativeResize(Eigen::Index(moved_.size()), K);
        moved_values_.row(Eigen::Index(i)).setZero();
      }
      const int ka = (k0 + 1) % 3, kb = (k0 + 2) % 3;
      const Eigen::Vector3d pa = vec(m.point(VertexHandle(int(pos[ka])))), pb = vec(m.point(VertexHandle(int(pos[kb]))));
      Eigen::Matrix<double, 3, 2> J;
      J.col(0) = pa - p0, J.col(1) = pb - p0;
      const double area = 0.5 * J.col(0).cross(J.col(1)).norm();
      if (!(area > 0)) continue;
      const Eigen::Vector2d c = (J.transpose() * J).ldlt().solve(J.transpose() * (p1 - p0));
      const auto l0 = s_->values->row(ren[k0]), la = s_->values->row(ren[ka]), lb = s_->values->row(ren[kb]);
      moved_values_.row(Eigen::Index(i)) += area * (l0 + c[0] * (la - l0) + c[1] * (lb - l0));
      weight[i] += area;
    }
    for (size_t i = 0; i < moved_.size(); ++i)
      moved_values_.row(Eigen::Index(i)) = weight[i] > 0 ? Eigen::RowVectorXd(moved_values_.row(Eigen::Index(i)) / weight[i])
                                                           : Eigen::RowVectorXd(s_->values->row(moved_[i]));
  }
  const double* moved_value(uint32_t r) const {
    size_t i = 0;
    while (moved_[i] != r) ++i;
    return moved_values_.row(Eigen::Index(i)).data();
  }

  // A boundary or feature vertex may only slide along its line: the line's other edge at v0,
  // (w, v0), becomes (w, v1), and v0 must lie within the tolerance of that new edge.
  bool lines_ok(const CollapseInfo& ci) {
    const OMesh& m = Base::mesh();
    const bool boundary = m.is_boundary(ci.v0);
    const bool feature = m.status(ci.v0).feature();
    if (!boundary && !feature) return true;
    const double tol = s_->options.feature_tolerance * s_->diagonal;
    for (OMesh::ConstVertexOHalfedgeIter h = m.cvoh_iter(ci.v0); h.is_valid(); ++h) {
      const VertexHandle w = m.to_vertex_handle(*h);
      if (w == ci.v1) continue;
      const OMesh::EdgeHandle e = m.edge_handle(*h);
      const bool on_line = (boundary && m.is_boundary(e)) || (feature && s_->feature[size_t(e.idx())]);
      if (on_line && segment_distance(vec(ci.p0), vec(m.point(w)), vec(ci.p1)) > tol) return false;
    }
    return true;
  }

  State* s_ = nullptr;
  double worst_ = -1;
  HalfedgeHandle worst_for_;  // worst_ is of this collapse (cleared by every priority call)
  std::vector<std::pair<FaceHandle, uint32_t>> changed_;
  bool moves_ = false;  // changed_ moves a corner's render vertex
  std::vector<uint32_t> moved_;  // those render vertices, and their estimated values at p1
  RowMatrixXd moved_values_;
  std::vector<std::pair<FaceHandle, int>> ring_;
  std::vector<FaceHandle> stack_;
};

size_t live_faces(const OMesh& m) {
  size_t n = 0;
  for (OMesh::ConstFaceIter f = m.faces_begin(); f != m.faces_end(); ++f) n += !m.status(*f).deleted();
  return n;
}

// The best legal collapse along a boundary edge (one face fewer), done; false if there is none.
bool boundary_collapse(OMesh& m, ModTransfer& module) {
  HalfedgeHandle best;
  float best_priority = 0;
  for (OMesh::HalfedgeIter h = m.halfedges_begin(); h != m.halfedges_end(); ++h) {
    if (m.status(*h).deleted() || !m.is_boundary(m.edge_handle(*h))) continue;
    const VertexHandle v0 = m.from_vertex_handle(*h);
    if (m.status(v0).locked() || !m.is_collapse_ok(*h)) continue;
    if (m.status(v0).feature() && !m.status(m.edge_handle(*h)).feature()) continue;
    ModTransfer::CollapseInfo ci(m, *h);
    if (ci.vl.is_valid() && ci.vr.is_valid()) continue;
    if (m.cw_rotated_halfedge_handle(m.cw_rotated_halfedge_handle(*h)) == *h) continue;  // one face at v0
    const float p = module.collapse_priority(ci);
    if (p < 0) continue;
    if (!best.is_valid() || p < best_priority) best = *h, best_priority = p;
  }
  if (!best.is_valid()) return false;
  ModTransfer::CollapseInfo ci(m, best);
  module.preprocess_collapse(ci);
  m.collapse(best);
  module.postprocess_collapse(ci);
  return true;
}

}  // namespace

namespace {

// The decimater's observer, turned into collapse counts for a progress bar. The decimater counts
// from 0 in every decimate_to_faces call; what it did not report is told when the call ends.
class CollapseProgress : public OpenMesh::Decimater::Observer {
 public:
  explicit CollapseProgress(const std::function<void(size_t)>& progress) : Observer(256), progress_(progress) {}
  void notify(size_t step) override {
    if (progress_ && step > told_) progress_(step - told_);
    told_ = step;
  }
  void finish_call(size_t collapses) {
    if (progress_ && collapses > told_) progress_(collapses - told_);
    told_ = 0;
  }

 private:
  const std::function<void(size_t)>& progress_;
  size_t told_ = 0;
};

SimplifyStats simplify_once(Mesh& mesh, RowMatrixXd& values, const SimplifyOptions& options, std::vector<uint32_t>* removed_to,
                            const std::function<void(size_t)>& progress, const std::vector<double>* variance) {
  const Stopwatch clock;
  SimplifyStats stats;
  stats.faces_before = mesh.num_faces();
  if (values.rows() != static_cast<Eigen::Index>(mesh.num_vertices()))
    throw InputError("simplify: " + std::to_string(values.rows()) + " value rows for " + std::to_string(mesh.num_vertices()) +
                     " render vertices");
  if (variance && variance->size() != mesh.num_vertices())
    throw InputError("simplify: " + std::to_string(variance->size()) + " variances for " + std::to_string(mesh.num_vertices()) +
                     " render vertices");
  if (!(options.min_angle_deg >= 0 && options.min_angle_deg < 60))
    throw InputError("simplify: the minimum angle must be in [0, 60) degrees, got " + std::to_string(options.min_angle_deg));
  if (!(options.value_scale > 0) || !(options.geometry_weight >= 0) || !(options.feature_tolerance >= 0) ||
      !(options.surface_tolerance > 0) || !(options.max_surface_tolerance >= options.surface_tolerance))
    throw InputError("simplify: value_scale must be > 0, geometry_weight and the feature tolerance >= 0, 0 < surface tolerance <= its maximum");
  if (options.budget >= mesh.num_faces()) {
    stats.faces_after = mesh.num_faces();
    stats.warning = "budget " + std::to_string(options.budget) + " is not below the input's " + std::to_string(mesh.num_faces()) +
                    " triangles: mesh left as it is";
    return stats;
  }

  State s;
  s.values = &values, s.options = options, s.variance = variance;
  if (mesh.normals.rows() == Eigen::Index(mesh.num_vertices())) s.normals = &mesh.normals;
  s.diagonal = mesh.positions.rows() ? std::max(bounds(mesh.positions).diagonal(), 1e-300) : 1;
  s.cos_min_angle = std::cos(options.min_angle_deg * M_PI / 180);
  s.surface_tolerance = options.surface_tolerance * s.diagonal;

  OMesh om;
  om.request_vertex_status();
  om.request_halfedge_status();
  om.request_edge_status();
  om.request_face_status();
  std::vector<VertexHandle> vh(static_cast<size_t>(mesh.positions.rows()));
  for (Eigen::Index p = 0; p < mesh.positions.rows(); ++p)
    vh[size_t(p)] = om.add_vertex(OMesh::Point(mesh.positions(p, 0), mesh.positions(p, 1), mesh.positions(p, 2)));
  std::vector<uint32_t> kept;  // our faces OpenMesh could not take
  omerr().disable();  // a refused face is counted, not printed
  for (uint32_t f = 0; f < mesh.num_faces(); ++f) {
    const Triangle& t = mesh.triangles[f];
    const uint32_t p[3] = {mesh.vertex_position[t[0]], mesh.vertex_position[t[1]], mesh.vertex_position[t[2]]};
    FaceHandle fh;
    if (p[0] != p[1] && p[1] != p[2] && p[0] != p[2]) fh = om.add_face(vh[p[0]], vh[p[1]], vh[p[2]]);
    if (!fh.is_valid()) {
      kept.push_back(f);
      continue;
    }
    s.corner_pos.push_back({p[0], p[1], p[2]});
    s.corner_render.push_back(t);
    s.source.push_back(mesh.source_face[f]);
  }
  omerr().enable();
  stats.kept_faces = kept.size();

  // Features: edges whose two faces see different render vertices at an end.
  s.feature.assign(om.n_edges(), 0);
  s.render_pos = mesh.vertex_position;
  s.moved.assign(mesh.num_vertices(), 0);
  std::vector<int> feature_edges(om.n_vertices(), 0);
  for (OMesh::EdgeIter e = om.edges_begin(); e != om.edges_end(); ++e) {
    if (!is_feature(om, s, *e)) continue;
    s.feature[size_t(e->idx())] = 1;
    om.status(*e).set_feature(true);
    const HalfedgeHandle h = om.halfedge_handle(*e, 0);
    ++feature_edges[size_t(om.from_vertex_handle(h).idx())], ++feature_edges[size_t(om.to_vertex_handle(h).idx())];
  }
  std::vector<char> lock(om.n_vertices(), 0);
  for (uint32_t f : kept)
    for (int k = 0; k < 3; ++k) lock[mesh.vertex_position[mesh.triangles[f][k]]] = 1;
  for (OMesh::VertexIter v = om.vertices_begin(); v != om.vertices_end(); ++v) {
    const int n = feature_edges[size_t(v->idx())];
    if (n > 0) om.status(*v).set_feature(true);
    if (locks(om, s, *v, n) || om.is_isolated(*v)) lock[size_t(v->idx())] = 1;
  }
  for (OMesh::VertexIter v = om.vertices_begin(); v != om.vertices_end(); ++v)
    if (lock[size_t(v->idx())]) om.status(*v).set_locked(true), stats.locked_vertices += !om.is_isolated(*v);

  // The budget counts the faces OpenMesh could not take too.
  const size_t target = options.budget > kept.size() ? options.budget - kept.size() : 0;
  {
    OpenMesh::Decimater::DecimaterT<OMesh> decimater(om);
    ModTransfer::Handle handle;
    decimater.add(handle);
    decimater.module(handle).set_state(&s);
    decimater.module(handle).set_binary(false);
    CollapseProgress told(progress);
    if (progress) decimater.set_observer(&told);
    if (!decimater.initialize()) throw InputError("simplify: OpenMesh's decimater did not initialise");
    // To target + 1 under the surface tolerance, doubling it while the guards stop short, up to
    // its maximum. The decimater counts deleted faces as faces, hence the offset.
    for (;;) {
      const size_t live = live_faces(om);
      if (live <= target + 1) break;
      const size_t collapses = decimater.decimate_to_faces(0, om.n_faces() - (live - (target + 1)));
      told.finish_call(collapses);
      stats.collapses += collapses;
      stats.surface_tolerance = s.surface_tolerance / s.diagonal;
      if (live_faces(om) <= target + 1 || 2 * s.surface_tolerance > options.max_surface_tolerance * s.diagonal * (1 + 1e-12)) break;
      s.surface_tolerance *= 2;
    }
    if (live_faces(om) == target + 1) {
      // The last face: a boundary collapse, under the tolerance relaxed as far as it may go.
      bool done = boundary_collapse(om, decimater.module(handle));
      while (!done && 2 * s.surface_tolerance <= options.max_surface_tolerance * s.diagonal * (1 + 1e-12)) {
        s.surface_tolerance *= 2;
        done = boundary_collapse(om, decimater.module(handle));
      }
      if (done) {
        ++stats.collapses;
        told.finish_call(1);
      } else {
        // The decimater counts deleted faces as faces: ask it for one collapse more.
        const size_t one = decimater.decimate_to_faces(0, om.n_faces() - 1);
        told.finish_call(one);
        stats.collapses += one;
        if (live_faces(om) + kept.size() != options.budget) {
          bool open = false;
          for (OMesh::EdgeIter e = om.edges_begin(); e != om.edges_end() && !open; ++e) open = !om.status(*e).deleted() && om.is_boundary(*e);
          stats.warning = "budget " + std::to_string(options.budget) + " cannot be met exactly: " +
                          (open ? "the guards allow no boundary collapse (a collapse elsewhere removes two faces)"
                                : "no boundary collapse is left (a closed surface has an even triangle count)") +
                          ": " + std::to_string(live_faces(om) + kept.size());
        }
      }
    }
  }
  if (const size_t n = live_faces(om) + kept.size(); n > options.budget)
    stats.warning = "budget " + std::to_string(options.budget) + " not reached: the guards (flips, minimum angle " +
                    short_number(options.min_angle_deg) + "°, boundaries and features, the surface moving by at most " +
                    short_number(100 * options.max_surface_tolerance) + "% of the diagonal) allow no further collapse at " +
                    std::to_string(n) + " triangles";

  // Gather the surviving faces (OpenMesh's order, then the kept ones) and compact.
  std::vector<Triangle> tri;
  std::vector<uint32_t> src;
  for (OMesh::FaceIter f = om.faces_begin(); f != om.faces_end(); ++f) {
    if (om.status(*f).deleted()) continue;
    tri.push_back(s.corner_render[size_t(f->idx())]);
    src.push_back(s.source[size_t(f->idx())]);
  }
  for (uint32_t f : kept) tri.push_back(mesh.triangles[f]), src.push_back(mesh.source_face[f]);
  std::vector<uint32_t> render_to(mesh.num_vertices(), UINT32_MAX), pos_to(size_t(mesh.positions.rows()), UINT32_MAX);
  std::vector<uint32_t> render_order, pos_order;
  for (Triangle& t : tri)
    for (uint32_t& v : t) {
      if (render_to[v] == UINT32_MAX) {
        render_to[v] = uint32_t(render_order.size());
        render_order.push_back(v);
        const uint32_t p = s.render_pos[v];
        if (pos_to[p] == UINT32_MAX) pos_to[p] = uint32_t(pos_order.size()), pos_order.push_back(p);
      }
      v = render_to[v];
    }
  Mesh out = mesh;
  out.positions.resize(static_cast<Eigen::Index>(pos_order.size()), 3);
  for (size_t i = 0; i < pos_order.size(); ++i) out.positions.row(Eigen::Index(i)) = mesh.positions.row(pos_order[i]);
  out.vertex_position.resize(render_order.size());
  out.normals.resize(static_cast<Eigen::Index>(render_order.size()), 3);
  if (mesh.has_uv()) out.uv.resize(static_cast<Eigen::Index>(render_order.size()), 2);
  if (mesh.has_colors()) out.colors.resize(static_cast<Eigen::Index>(render_order.size()), 3);
  RowMatrixXd vals(static_cast<Eigen::Index>(render_order.size()), values.cols());
  for (size_t i = 0; i < render_order.size(); ++i) {
    const uint32_t v = render_order[i];
    out.vertex_position[i] = pos_to[s.render_pos[v]];
    if (s.moved[v]) stats.moved.push_back(uint32_t(i));
    out.normals.row(Eigen::Index(i)) = mesh.normals.row(v);
    if (mesh.has_uv()) out.uv.row(Eigen::Index(i)) = mesh.uv.row(v);
    if (mesh.has_colors()) out.colors.row(Eigen::Index(i)) = mesh.colors.row(v);
    vals.row(Eigen::Index(i)) = values.row(v);
  }
  out.triangles = std::move(tri);
  out.source_face = std::move(src);
  mesh = std::move(out);
  values = std::move(vals);
  if (removed_to) *removed_to = std::move(render_to);

  stats.refused_flip = s.refused_flip, stats.refused_angle = s.refused_angle, stats.refused_line = s.refused_line;
  stats.refused_crease_side = s.refused_side, stats.refused_surface = s.refused_surface;
  stats.corner_collapses = s.corner_collapses;
  stats.surface_tolerance = s.surface_tolerance / s.diagonal;
  stats.faces_after = mesh.num_faces();
  stats.min_angle_after_deg = min_angle_deg(mesh);
  for (double a : face_min_angles_deg(mesh)) stats.faces_below_min_angle += a < options.min_angle_deg;
  stats.seconds = clock.total();
  return stats;
}

}  // namespace

SimplifyStats simplify(Mesh& mesh, RowMatrixXd& values, const SimplifyOptions& options, std::vector<uint32_t>* removed_to,
                       const std::function<void(size_t)>& progress, const std::vector<double>* variance) {
  if (!(options.max_surface_tolerance > options.surface_tolerance) || options.budget >= mesh.num_faces())
    return simplify_once(mesh, values, options, removed_to, progress, variance);
  // First under the surface tolerance alone. Relaxing it is worth its damage only where it gets
  // there, or at least halfway from where the strict run stopped: sibenik's locked crease corners
  // stop both near 35k of a 19k budget, and the relaxed run's few hundred more collapses, each
  // moving the surface by up to 4% of the diagonal, more than doubled its error.
  const Stopwatch clock;
  Mesh relaxed = mesh;
  RowMatrixXd relaxed_values = values;
  SimplifyOptions strict = options;
  strict.max_surface_tolerance = options.surface_tolerance;
  std::vector<uint32_t> strict_to;
  SimplifyStats st = simplify_once(mesh, values, strict, removed_to ? &strict_to : nullptr, progress, variance);
  if (st.faces_after > options.budget) {
    std::vector<uint32_t> relaxed_to;
    SimplifyStats rt = simplify_once(relaxed, relaxed_values, options, removed_to ? &relaxed_to : nullptr, progress, variance);
    // Kept if it closes at least half the gap the strict run left.
    if (2 * (st.faces_after - std::max(rt.faces_after, options.budget)) >= st.faces_after - options.budget) {
      mesh = std::move(relaxed), values = std::move(relaxed_values), strict_to = std::move(relaxed_to), st = rt;
    } else {
      st.warning += " (relaxing the surface tolerance to " + short_number(100 * options.max_surface_tolerance) +
                    "% of the diagonal only reached " + std::to_string(rt.faces_after) + ", kept the strict run)";
    }
  }
  if (removed_to) *removed_to = std::move(strict_to);
  st.seconds = clock.total();
  return st;
}

}  // namespace prtsub
