// Budgeted adaptive refinement by longest-edge bisection.
//
// Topology is kept over positions: each face corner slot links to the next slot of the same
// position edge in a ring around it (the face across, for a manifold edge; k faces in turn on a
// non-manifold edge shared by k > 2), or marks the edge a boundary. Links tolerate faces that
// wind an edge the same way. Splitting an edge inserts one position at its midpoint and splits
// every face on it, so the mesh is conforming after every split: an edge of k faces adds k
// triangles, a boundary edge one. Non-manifold edges are split like any other: left alone (as
// refinement once did) they end up the longest edge of every face beside them, which are then
// sliced along their shorter edges again and again (17% of a voxel world's faces fell below 1°). Each face
// sees the edge through its own render vertices: faces across a smooth edge share their
// corners and so share the new render vertex; across a crease each side gets its own at the
// same position, interpolated from its own corners.
//
// Faces wait in an indexed max-heap keyed by (sum of their edges' errors, area), ties by id.
// A popped face is refined along its longest-edge propagation path (Rivara): walk to the
// neighbour across the longest edge while that neighbour has a longer one, split the terminal
// edge (the longest of both its faces), and repeat until the popped face itself is split.
// Lengths are compared as (length, edge key), a total order, so every walk terminates, and
// longest-edge bisection keeps every angle above half the smallest input angle. On an edge of
// k faces the edge is terminal only when it is the longest of all k. The one exception is a
// face without area: its quality cannot be kept, so the walk does not enter it, and it is split
// along whatever edge its neighbour needs (which keeps it from sending paths along a collinear
// strip, and keeps it from seeding slivers in its neighbours).
//
// Work comes in batches: pop `batch` faces and split them with provisional values (linear
// interpolation), then ask the signal for the new vertices' true values all at once (Embree
// traces them in parallel), then key the new faces. Keys go stale within a batch, so a batch is
// at most 1/16 of the current faces (on the 32-triangle Cornell box a fixed 256 spent the first
// batches on starting keys) and at most 1/64 of the triangles the run adds: a short run in
// batches of 1/16 of the faces splits wide on starting keys where it should go deep (mori_knob's
// --refine auto adds 2,394 triangles to 9,576: in batches of 256, 1.91% eval error; of 37,
// 1.07%, as in batches of one). Results depend on the batch size but not on threads. The budget is exact except where parity forbids it: a closed surface has
// 3F = 2E, so F is even, and with no boundary edge left to split an odd budget stops one
// short (reported as a warning).
#include "prtsub/subdiv/refine.h"

#include <algorithm>
#include <cmath>

#include "prtsub/subdiv/adjacency.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/indexed_heap.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

using Key = std::pair<double, double>;  // (error, area)

inline uint64_t edge_key(uint32_t a, uint32_t b) { return (uint64_t(std::min(a, b)) << 32) | std::max(a, b); }

// Per corner slot 3f + k (the edge from corner k to k + 1): the next slot of the same edge in
// its ring (the face across it, on a manifold edge), or one of these. kUnsplittable marks the
// rare edge a face has twice (a face with a repeated position), which no split can keep valid.
constexpr uint32_t kBoundary = UINT32_MAX, kUnsplittable = UINT32_MAX - 1;
// A batch pops at most 1/kBatchShare of the current faces (and at most RefineOptions::batch).
constexpr size_t kBatchShare = 16;
// ... and at most 1/kAddedShare of the triangles the run adds.
constexpr size_t kAddedShare = 64;

class Refiner {
 public:
  Refiner(Mesh& mesh, RowMatrixXd& values, RowMatrixXd* attributes, RefinementSignal& signal)
      : mesh_(mesh), values_out_(values), attr_out_(attributes), signal_(signal) {
    K_ = static_cast<int>(values.cols());
    A_ = attributes ? static_cast<int>(attributes->cols()) : 0;
    for (Eigen::Index i = 0; i < mesh.positions.rows(); ++i) pos_.push_back(mesh.positions.row(i).transpose());
    vpos_ = mesh.vertex_position;
    for (Eigen::Index i = 0; i < mesh.normals.rows(); ++i) nrm_.push_back(mesh.normals.row(i).transpose());
    uv_.assign(mesh.uv.data(), mesh.uv.data() + mesh.uv.size());
    rgb_.assign(mesh.colors.data(), mesh.colors.data() + mesh.colors.size());
    val_.assign(values.data(), values.data() + values.size());
    if (A_) attr_.assign(attributes->data(), attributes->data() + attributes->size());
    tri_ = mesh.triangles;
    src_ = mesh.source_face;
    link_faces();
    const double diag = mesh.positions.rows() ? bounds(mesh.positions).diagonal() : 0.0;
    min_area_ = (1e-7 * diag) * (1e-7 * diag);  // the loader's zero-area threshold
  }

  size_t non_manifold_edges() const { return non_manifold_edges_; }
  size_t unsplittable_edges() const { return unsplittable_edges_; }
  size_t faces() const { return tri_.size(); }

  // Everything grows with every split; sizing it for the budget once avoids repeated copies
  // and page faults (a split adds at most two faces and, at a crease, two render vertices).
  void reserve(size_t budget) {
    const size_t extra = budget > tri_.size() ? budget - tri_.size() : 0;
    tri_.reserve(budget);
    src_.reserve(budget);
    pos_.reserve(pos_.size() + extra);
    vpos_.reserve(vpos_.size() + extra);
    nrm_.reserve(nrm_.size() + extra);
    uv_.reserve(uv_.size() + (uv_.empty() ? 0 : 2 * extra));
    rgb_.reserve(rgb_.size() + (rgb_.empty() ? 0 : 3 * extra));
    val_.reserve(val_.size() + extra * static_cast<size_t>(K_));
    attr_.reserve(attr_.size() + extra * static_cast<size_t>(A_));
    link_.reserve(3 * budget);
    heap_capacity_ = budget;
  }

  // Runs batches until the budget is met or nothing is left to split. `key_of` gives a face's
  // key, or nullopt-like (first < 0) when it should not be split.
  template <class KeyFn>
  void run(size_t budget, size_t batch, KeyFn&& key_of, RefineStats& stats) {
    IndexedHeap<Key> heap;
    heap.reserve(heap_capacity_);
    for (uint32_t f = 0; f < tri_.size(); ++f) {
      Key k = key_of(f);
      if (k.first >= 0) heap.push(f, k);
    }
    heap_ = &heap;
    const size_t to_add = budget > tri_.size() ? budget - tri_.size() : 0;
    const size_t add_cap = std::max<size_t>(1, to_add / kAddedShare);
    while (tri_.size() < budget && !heap.empty()) {
      pending_.clear();
      dirty_.clear();
      // Keys go stale within a batch (new faces wait for their values), so a batch is at most a
      // share of the faces there are (on a 32-triangle scene a batch of 256 would spend the
      // first eight times the mesh on its starting keys) and of what this run adds.
      const size_t n = std::min({batch, std::max<size_t>(1, tri_.size() / kBatchShare), add_cap});
      for (size_t i = 0; i < n && tri_.size() < budget && !heap.empty(); ++i) {
        uint32_t t = heap.pop();
        if (!lepp(t, budget, stats)) {
          // The split needs more triangles than are left: end on smaller splits if any.
          heap.push(t, key_of(t));
          if (!finish_budget(budget, heap, stats)) {
            stats.warning = "budget " + std::to_string(budget) + " cannot be met exactly: no split of " +
                            std::to_string(budget - tri_.size()) + " triangle(s) is left (a closed surface has an even "
                            "triangle count): stopped at " + std::to_string(tri_.size());
          }
          break;
        }
      }
      finish_batch(stats);
      for (uint32_t f : dirty_) {
        Key k = key_of(f);
        if (k.first >= 0) heap.push(f, k); else heap.remove(f);
      }
      if (!stats.warning.empty()) break;
    }
    heap_ = nullptr;
  }

  Key error_key(uint32_t f) const {
    double e = 0;
    for (int k = 0; k < 3; ++k) {
      uint32_t a = tri_[f][k], b = tri_[f][(k + 1) % 3];
      if (link_[3 * size_t(f) + size_t(k)] == kUnsplittable) continue;  // never split: no say
      EdgeView v{pos_[vpos_[a]], pos_[vpos_[b]], nrm_[a], nrm_[b], &val_[size_t(a) * K_], &val_[size_t(b) * K_], K_};
      e += signal_.edge_error(v);
    }
    const double a = area(f);
    // A face without area holds no surface error, whatever its edges say: a zero-area sliver
    // along a long edge between a lit and a dark vertex would otherwise keep the queue busy
    // forever, each split making two slivers with half the key. It is still split when a
    // neighbour's path needs it, so the mesh stays conforming.
    if (longest_edge(f) < 0 || !(a > min_area_)) return {-1, 0};
    if (f < extra_.size()) e += extra_[f];
    return {e, a};
  }

  // Asks the signal for interior probes of every current face (see RefinementSignal).
  void probe(RefineStats& stats) {
    std::vector<FaceProbe> faces(tri_.size());
    for (uint32_t f = 0; f < tri_.size(); ++f) {
      const Triangle& t = tri_[f];
      Eigen::Vector3d n = nrm_[t[0]] + nrm_[t[1]] + nrm_[t[2]];
      if (!(n.norm() > 1e-12)) n = nrm_[t[0]];
      faces[f] = {(pos_[vpos_[t[0]]] + pos_[vpos_[t[1]]] + pos_[vpos_[t[2]]]) / 3, n.normalized(), area(f),
                  &val_[size_t(t[0]) * K_], &val_[size_t(t[1]) * K_], &val_[size_t(t[2]) * K_], K_};
    }
    const Stopwatch clock;
    signal_.probe_faces(faces, extra_);
    stats.seconds_signal += clock.total();
    stats.probed_faces = extra_.size();
  }

  Key length_key(uint32_t f, double max_edge) const {
    int k = longest_edge(f);
    if (k < 0) return {-1, 0};
    double len = (pos_[pos_of(f, k)] - pos_[pos_of(f, k + 1)]).norm();
    return len > max_edge ? Key{len, 0} : Key{-1, 0};
  }

  void write_back() {
    mesh_.positions.resize(static_cast<Eigen::Index>(pos_.size()), 3);
    for (size_t i = 0; i < pos_.size(); ++i) mesh_.positions.row(static_cast<Eigen::Index>(i)) = pos_[i].transpose();
    mesh_.vertex_position = vpos_;
    mesh_.normals.resize(static_cast<Eigen::Index>(nrm_.size()), 3);
    for (size_t i = 0; i < nrm_.size(); ++i) mesh_.normals.row(static_cast<Eigen::Index>(i)) = nrm_[i].transpose();
    if (!uv_.empty()) mesh_.uv = Eigen::Map<RowMatrixX2d>(uv_.data(), static_cast<Eigen::Index>(vpos_.size()), 2);
    if (!rgb_.empty()) mesh_.colors = Eigen::Map<RowMatrixX3d>(rgb_.data(), static_cast<Eigen::Index>(vpos_.size()), 3);
    mesh_.triangles = tri_;
    mesh_.source_face = src_;
    values_out_ = Eigen::Map<RowMatrixXd>(val_.data(), static_cast<Eigen::Index>(vpos_.size()), K_);
    if (attr_out_) *attr_out_ = Eigen::Map<RowMatrixXd>(attr_.data(), static_cast<Eigen::Index>(vpos_.size()), A_);
  }

 private:
  uint32_t pos_of(uint32_t f, int k) const { return vpos_[tri_[f][k % 3]]; }
  double area(uint32_t f) const {
    return 0.5 * (pos_[pos_of(f, 1)] - pos_[pos_of(f, 0)]).cross(pos_[pos_of(f, 2)] - pos_[pos_of(f, 0)]).norm();
  }

  // Rings every corner slot with the slots of the same position edge in the other faces on it:
  // half-edges grouped by position edge, a run of one is a boundary, two a pair (in either
  // winding), more a ring in slot order. Splits keep the links up to date, so refinement never
  // looks an edge up by key (a hash lookup per step cost about a third of its time).
  void link_faces() {
    const EdgeAdjacency adj = edge_adjacency(tri_, &vpos_);
    link_.assign(tri_.size() * 3, kBoundary);
    for (size_t e = 0; e < adj.num_edges(); ++e) {
      const uint32_t* h = adj.edge_begin(e);
      const uint32_t n = adj.valence(e);
      if (n < 2) continue;
      bool twice = false;  // a face on its own edge twice
      for (uint32_t i = 1; i < n; ++i) twice |= h[i] / 3 == h[i - 1] / 3;  // h is sorted
      if (n > 2) ++non_manifold_edges_;
      if (twice) ++unsplittable_edges_;
      for (uint32_t i = 0; i < n; ++i) link_[h[i]] = twice ? kUnsplittable : h[(i + 1) % n];
    }
  }
  // Puts slot `to` in the place of slot `from` in from's ring (from is about to be reused).
  void take_place(uint32_t from, uint32_t to) {
    const uint32_t next = link_[from];
    link_[to] = next;
    if (next >= kUnsplittable) return;
    uint32_t s = next;
    while (link_[s] != from) s = link_[s];
    link_[s] = to;
  }
  // Links slots that now share one edge into a ring (one: a boundary).
  void ring(const uint32_t* slots, size_t n) {
    for (size_t i = 0; i < n; ++i) link_[slots[i]] = n == 1 ? kBoundary : slots[(i + 1) % n];
  }

  // Corner k whose edge (k, k+1) is the face's longest splittable edge in the total order
  // (length, key), or -1 when none is splittable.
  int longest_edge(uint32_t f) const {
    int best = -1;
    double best_len = -1;
    uint64_t best_key = 0;
    for (int k = 0; k < 3; ++k) {
      if (link_[3 * size_t(f) + size_t(k)] == kUnsplittable) continue;
      uint32_t a = pos_of(f, k), b = pos_of(f, k + 1);
      uint64_t key = edge_key(a, b);
      double len = (pos_[a] - pos_[b]).squaredNorm();
      if (len > best_len || (len == best_len && key > best_key)) best = k, best_len = len, best_key = key;
    }
    return best;
  }

  // Refines along the longest-edge path from t until t is split. Returns false if the next
  // split would exceed the budget. The path is kept as a stack: after a terminal split only
  // the two faces on that edge changed, so the walk resumes one step back instead of from t.
  // On meshes of long skinny triangles (architecture) a path runs dozens of faces deep, and
  // restarting from t would make each path cost its length squared.
  bool lepp(uint32_t t, size_t budget, RefineStats& stats) {
    path_.assign(1, t);
    ++stats.faces_popped;
    for (;;) {
      ++stats.walk_steps;
      if (tri_.size() >= budget) return true;  // the path may end the budget before t splits
      if (path_.empty()) path_.push_back(t);
      const uint32_t cur = path_.back();
      const int k = longest_edge(cur);
      if (k < 0) return true;  // nothing splittable in t (only t can lack a splittable edge)
      const uint32_t slot = 3 * cur + uint32_t(k);
      // Every other face on the edge must have it as its longest too, or the path goes there.
      uint32_t longer = UINT32_MAX;
      size_t faces_on_edge = 1;
      bool hit_t = cur == t;
      if (link_[slot] != kBoundary) {
        for (uint32_t s = link_[slot]; s != slot; s = link_[s], ++faces_on_edge) {
          const uint32_t other = s / 3;
          hit_t |= other == t;
          // A neighbour without area has no quality to keep: split the shared edge now rather
          // than follow the path along a degenerate (collinear) strip, which only makes more.
          if (longer == UINT32_MAX && area(other) > min_area_ && longest_edge(other) != int(s % 3)) longer = other;
        }
      }
      if (longer != UINT32_MAX) {
        path_.push_back(longer);  // a neighbour has a longer edge: refine there first
        continue;
      }
      if (tri_.size() + faces_on_edge > budget) return false;
      split(cur, k, stats);
      if (hit_t) return true;
      path_.pop_back();  // cur was split; its predecessor's longest edge still leads here
    }
  }

  // Ends the budget when the popped face's split needs more triangles than are left (one left
  // on a closed surface; fewer than k left for an edge of k faces): while any split fits, splits
  // the edge of the highest-ranked face that is terminal (the longest of every face on it, so
  // the angle bound holds), and only if none is, any edge that fits (a boundary edge, say).
  bool finish_budget(size_t budget, IndexedHeap<Key>& heap, RefineStats& stats) {
    while (tri_.size() < budget) {
      const size_t left = budget - tri_.size();
      uint32_t best = UINT32_MAX;
      int best_corner = 0;
      bool best_terminal = false;
      Key best_key{0, 0};
      for (uint32_t f = 0; f < tri_.size(); ++f) {
        // Faces split in this batch wait for their keys, and faces without area have none.
        const Key key = heap.contains(f) ? heap.key(f) : Key{-1, 0};
        const int longest = longest_edge(f);
        for (int k = 0; k < 3; ++k) {
          const uint32_t slot = 3 * f + uint32_t(k);
          if (link_[slot] == kUnsplittable) continue;
          size_t n = 1;
          bool terminal = k == longest;
          if (link_[slot] != kBoundary)
            for (uint32_t s = link_[slot]; s != slot && n <= left; s = link_[s], ++n)
              terminal &= !(area(s / 3) > min_area_) || longest_edge(s / 3) == int(s % 3);
          if (n > left) continue;
          if (best == UINT32_MAX || terminal > best_terminal || (terminal == best_terminal && key > best_key))
            best = f, best_corner = k, best_terminal = terminal, best_key = key;
        }
      }
      if (best == UINT32_MAX) return false;
      split(best, best_corner, stats);
    }
    return true;
  }

  // Splits the edge of face f0 from corner k0 to k0 + 1, in every face on it (its ring).
  void split(uint32_t f0, int k0, RefineStats& stats) {
    const uint32_t s0 = 3 * f0 + uint32_t(k0);
    ring_.assign(1, s0);
    if (link_[s0] != kBoundary)
      for (uint32_t s = link_[s0]; s != s0; s = link_[s]) ring_.push_back(s);
    const uint32_t p = pos_of(f0, k0);  // the edge is (p, q)
    const uint32_t m = static_cast<uint32_t>(pos_.size());
    pos_.push_back(0.5 * (pos_[p] + pos_[pos_of(f0, k0 + 1)]));
    made_.clear();  // (render pair, new render vertex) of this split
    half_p_.clear(), half_q_.clear();
    for (const uint32_t slot : ring_) {
      const uint32_t f = slot / 3, k = slot % 3, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      const uint32_t a = tri_[f][k], b = tri_[f][k1], c = tri_[f][k2];
      const uint64_t pair_key = edge_key(a, b);
      uint32_t mv = UINT32_MAX;
      for (const auto& [key, v] : made_)
        if (key == pair_key) mv = v;
      if (mv == UINT32_MAX) {
        mv = new_vertex(m, a, b, f);
        made_.emplace_back(pair_key, mv);
      }
      const uint32_t g = static_cast<uint32_t>(tri_.size());
      Triangle tf = tri_[f], tg;
      tf[k1] = mv;  // f = (a, mv, c) in f's own corner order
      tg[k] = mv, tg[k1] = b, tg[k2] = c;  // g = (mv, b, c)
      tri_[f] = tf;
      tri_.push_back(tg);
      src_.push_back(src_[f]);
      // Links: g takes f's edge (b, c); (mv, c) joins f and g; (c, a) stays with f.
      link_.insert(link_.end(), {kBoundary, kBoundary, kBoundary});
      take_place(3 * f + k1, 3 * g + k1);
      link_[3 * f + k1] = 3 * g + k2, link_[3 * g + k2] = 3 * f + k1;
      // (a, mv) is slot 3f + k and (mv, b) slot 3g + k; sort them by the end they share.
      const bool a_is_p = vpos_[a] == p;
      half_p_.push_back(a_is_p ? 3 * f + k : 3 * g + k);
      half_q_.push_back(a_is_p ? 3 * g + k : 3 * f + k);
      if (heap_) heap_->remove(f);
      if (f < extra_.size()) extra_[f] = 0;  // a probe speaks for the face it was taken in only
      dirty_.push_back(f);
      dirty_.push_back(g);
    }
    ring(half_p_.data(), half_p_.size());
    ring(half_q_.data(), half_q_.size());
    ++stats.splits;
    if (ring_.size() == 1) ++stats.boundary_splits;
    if (ring_.size() > 2) ++stats.non_manifold_splits;
  }

  uint32_t new_vertex(uint32_t position, uint32_t a, uint32_t b, uint32_t face) {
    const uint32_t v = static_cast<uint32_t>(vpos_.size());
    vpos_.push_back(position);
    Eigen::Vector3d n = nrm_[a] + nrm_[b];
    if (!(n.norm() > 1e-12)) {  // opposite normals: take the face's
      n = (pos_[pos_of(face, 1)] - pos_[pos_of(face, 0)]).cross(pos_[pos_of(face, 2)] - pos_[pos_of(face, 0)]);
      if (!(n.norm() > 0)) n = nrm_[a];
    }
    nrm_.push_back(n.normalized());
    if (!uv_.empty()) {  // a seam's two sides are different render pairs, each split on its own
      const double u = 0.5 * (uv_[2 * size_t(a)] + uv_[2 * size_t(b)]), w = 0.5 * (uv_[2 * size_t(a) + 1] + uv_[2 * size_t(b) + 1]);
      uv_.push_back(u), uv_.push_back(w);
    }
    for (size_t c = 0; !rgb_.empty() && c < 3; ++c) rgb_.push_back(0.5 * (rgb_[3 * size_t(a) + c] + rgb_[3 * size_t(b) + c]));
    for (int i = 0; i < K_; ++i) val_.push_back(0.5 * (val_[size_t(a) * K_ + i] + val_[size_t(b) * K_ + i]));
    for (int i = 0; i < A_; ++i) attr_.push_back(0.5 * (attr_[size_t(a) * A_ + i] + attr_[size_t(b) * A_ + i]));
    pending_.push_back({v, a, b, position, pos_[position], nrm_.back()});
    return v;
  }

  void finish_batch(RefineStats& stats) {
    if (pending_.empty()) return;
    const Stopwatch clock;
    RowMatrixXd parent(static_cast<Eigen::Index>(pending_.size()), K_), out(static_cast<Eigen::Index>(pending_.size()), K_);
    for (size_t i = 0; i < pending_.size(); ++i)
      for (int c = 0; c < K_; ++c) parent(static_cast<Eigen::Index>(i), c) = val_[size_t(pending_[i].index) * K_ + c];
    signal_.compute_values(pending_, parent, out);
    for (size_t i = 0; i < pending_.size(); ++i)
      for (int c = 0; c < K_; ++c) val_[size_t(pending_[i].index) * K_ + c] = out(static_cast<Eigen::Index>(i), c);
    stats.seconds_signal += clock.total();
    stats.new_vertices += pending_.size();
    ++stats.batches;
    std::sort(dirty_.begin(), dirty_.end());
    dirty_.erase(std::unique(dirty_.begin(), dirty_.end()), dirty_.end());
  }

  Mesh& mesh_;
  RowMatrixXd& values_out_;
  RowMatrixXd* attr_out_;
  RefinementSignal& signal_;
  int K_ = 0, A_ = 0;
  double min_area_ = 0;
  size_t heap_capacity_ = 0;
  std::vector<double> extra_;  // probe keys of faces not yet split
  std::vector<Eigen::Vector3d> pos_, nrm_;
  std::vector<double> uv_;  // 2 per render vertex, or empty
  std::vector<double> rgb_;  // 3 per render vertex (linear colour), or empty
  std::vector<uint32_t> vpos_, src_;
  std::vector<double> val_, attr_;
  std::vector<Triangle> tri_;
  std::vector<uint32_t> link_;  // per corner slot: see kBoundary
  size_t non_manifold_edges_ = 0, unsplittable_edges_ = 0;
  std::vector<NewVertex> pending_;
  std::vector<uint32_t> dirty_;
  std::vector<uint32_t> path_;
  std::vector<uint32_t> ring_, half_p_, half_q_;  // split()'s scratch
  std::vector<std::pair<uint64_t, uint32_t>> made_;
  IndexedHeap<Key>* heap_ = nullptr;
};

}  // namespace

std::vector<double> face_min_angles_deg(const Mesh& mesh) {
  std::vector<double> out(mesh.triangles.size(), 0.0);
  for (size_t f = 0; f < out.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    Eigen::Vector3d p[3] = {mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2])};
    if (!((p[1] - p[0]).cross(p[2] - p[0]).norm() > 0)) continue;
    double best = 180;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d a = p[(k + 1) % 3] - p[k], b = p[(k + 2) % 3] - p[k];
      best = std::min(best, std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0)) * 180 / M_PI);
    }
    out[f] = best;
  }
  return out;
}

double min_angle_deg(const Mesh& mesh) {
  double best = 180;
  for (double a : face_min_angles_deg(mesh))
    if (a > 0) best = std::min(best, a);
  return best;
}

namespace {
void angle_stats(const Mesh& mesh, double& min_deg, size_t& below_1deg) {
  min_deg = 180, below_1deg = 0;
  for (double a : face_min_angles_deg(mesh)) {
    if (a > 0) min_deg = std::min(min_deg, a);
    below_1deg += a < 1;
  }
}
}  // namespace

RefineStats refine_adaptive(Mesh& mesh, RowMatrixXd& values, RefinementSignal& signal, const RefineOptions& options,
                            RowMatrixXd* attributes) {
  const Stopwatch clock;
  RefineStats stats;
  angle_stats(mesh, stats.min_angle_before_deg, stats.faces_below_1deg_before);
  if (options.budget <= mesh.num_faces()) {
    stats.warning = "budget " + std::to_string(options.budget) + " is not above the input's " +
                    std::to_string(mesh.num_faces()) + " triangles: mesh left as it is";
    stats.min_angle_after_deg = stats.min_angle_before_deg;
    stats.faces_below_1deg_after = stats.faces_below_1deg_before;
    return stats;
  }
  if (mesh.has_uv() && static_cast<size_t>(mesh.uv.rows()) != mesh.num_vertices())
    throw InputError("refine: the mesh has " + std::to_string(mesh.uv.rows()) + " UVs for " +
                     std::to_string(mesh.num_vertices()) + " render vertices");
  if (mesh.has_colors() && static_cast<size_t>(mesh.colors.rows()) != mesh.num_vertices())
    throw InputError("refine: the mesh has " + std::to_string(mesh.colors.rows()) + " colours for " +
                     std::to_string(mesh.num_vertices()) + " render vertices");
  Refiner r(mesh, values, attributes, signal);
  stats.non_manifold_edges = r.non_manifold_edges();
  stats.non_manifold_edges_kept = r.unsplittable_edges();
  r.reserve(options.budget);
  const size_t batch = std::max<size_t>(options.batch, 1);
  if (options.max_edge > 0) {
    r.run(options.budget, batch, [&](uint32_t f) { return r.length_key(f, options.max_edge); }, stats);
    stats.pre_refinement_splits = stats.splits;
  }
  if (stats.warning.empty()) {
    r.probe(stats);
    r.run(options.budget, batch, [&](uint32_t f) { return r.error_key(f); }, stats);
  }
  r.write_back();
  angle_stats(mesh, stats.min_angle_after_deg, stats.faces_below_1deg_after);
  stats.seconds_total = clock.total();
  return stats;
}

}  // namespace prtsub
