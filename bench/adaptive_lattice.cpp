// Would refining a vertex's lattice only where its visibility changes beat the uniform lattice?
// A prototype for issue 15, point 2 (a better estimator, not a better spread of the same one),
// measured at a random subset of one scene's vertices: the shadowed transfer of order ORDER
// (AO at order 1), with the control variate β = 1 (only the blocked part is estimated), by
//   - "uniform": one doubling lattice of N rays (sampling.h), one random shift;
//   - "two halves": two lattices of N/2 with independent shifts, the shape shadowed_transfer
//     traces (its halves give the variance and each other's β);
//   - "own" (with OWN=1 in the environment): a lattice of B rays whose cells are split, level by
//     level, where a point's visibility differs from one of its 8 nearest lattice neighbours'.
//     Cell q of lattice j (area 1/M_j) splits into q and its partner, q's point plus the odd
//     point of lattice j + 1 nearest 0, so the doubled lattice's cells tile the old one's and
//     stay local. The estimate is Σ over leaf cells of area · integrand at the cell's point. The
//     split depends on the cell's own sample, which biases it (a hit on a thin occluder is
//     halved by the split, a miss keeps its whole weight);
//   - "cross": two halves of B rays each, each split wherever the *other* half saw a boundary
//     (a point differing from a neighbour) within rho lattice spacings: each half's partition is
//     independent of its own samples.
// All against one lattice of 256·2^REF_LEVELS rays at another shift; each estimator at four
// shifts per vertex. Prints the mean squared error over the vertices (summed over the values)
// and the mean rays per vertex.
// usage: bash bench/adaptive_lattice.sh BUILD SCENE [ORDER] [VERTICES] [REF_LEVELS]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/sh.h"
#include "prtsub/prt/transfer.h"
#include "prtsub/prt/vertex_top_up.h"
#include "prtsub/subdiv/mesh_io.h"
#include "prtsub/subdiv/random.h"
#include "random_vertices.h"

using namespace prtsub;

namespace {

struct Vertex : BenchVertex {
  double s, u;  // the lattice's shift
};

// The squared length of (x, y) on the unit torus.
double wrapped2(double x, double y) {
  x -= std::round(x), y -= std::round(y);
  return x * x + y * y;
}

// Index offsets m of the k shortest vectors of lattice (M, a) on the torus.
std::vector<uint32_t> neighbour_offsets(uint32_t M, uint32_t a, int k) {
  std::vector<std::pair<double, uint32_t>> v;
  for (uint32_t q = 1; q < M; ++q) {
    v.push_back({wrapped2(double(q) / M, double((uint64_t(q) * a) % M) / M), q});
  }
  std::partial_sort(v.begin(), v.begin() + std::min<size_t>(v.size(), size_t(k)), v.end());
  std::vector<uint32_t> out;
  for (int i = 0; i < k && i < int(v.size()); ++i) out.push_back(v[size_t(i)].second);
  return out;
}

struct Lattices {
  uint32_t base;
  std::vector<uint32_t> a;
  std::vector<std::vector<uint32_t>> near;
  std::vector<uint64_t> partner;  // partner[j]: the odd index of lattice j + 1 nearest 0
  // Rank-1 doublings, as prtsub made them up to 2026-12-07: a_{j+1} is a_j or a_j + M_j, the
  // better by Zaremba's index (the library now also weighs a third lattice, not rank-1).
  Lattices(uint32_t b, int levels) : base(b), a{doubling_lattice(b, 0).generator} {
    for (int j = 1; j <= levels; ++j) {
      const uint32_t M = b << j, keep = a.back(), moved = a.back() + (M >> 1);
      a.push_back(zaremba_index(M, moved) > zaremba_index(M, keep) ? moved : keep);
    }
    for (int j = 0; j <= levels; ++j) near.push_back(neighbour_offsets(b << j, a[size_t(j)], 8));
    for (int j = 0; j < levels; ++j) {
      const uint64_t M = uint64_t(b) << (j + 1);
      double best = 1e9;
      uint64_t o = 1;
      for (uint64_t q = 1; q < M; q += 2) {
        const double d = wrapped2(double(q) / double(M), double((q * a[size_t(j) + 1]) % M) / double(M));
        if (d < best) best = d, o = q;
      }
      partner.push_back(o);
    }
  }
  std::vector<Eigen::Vector2d> points(int j) const {
    std::vector<Eigen::Vector2d> uv;
    for (uint64_t q = 0; q < (uint64_t(base) << j); ++q) uv.push_back(point(j, q));
    return uv;
  }
  Eigen::Vector2d point(int j, uint64_t q) const {
    const uint64_t M = uint64_t(base) << j;
    return {double(q) / double(M), double((q * a[size_t(j)]) % M) / double(M)};
  }
};

// Traces the given lattice points (unshifted) from v: visible[k] is 1 where ray k escapes.
void trace(const RayScene& scene, const Vertex& v, const std::vector<Eigen::Vector2d>& uv, std::vector<char>& visible) {
  std::vector<RTCRay> rays(uv.size());
  for (size_t k = 0; k < uv.size(); ++k) {
    double u = uv[k].x() + v.s, w = uv[k].y() + v.u;
    u -= std::floor(u), w -= std::floor(w);
    const Eigen::Vector3d d = cosine_direction(u, w);
    const Eigen::Vector3d dir = (d.x() * v.t + d.y() * v.b + d.z() * v.n).normalized();
    init_occlusion_ray(rays[k], v.origin, dir.cast<float>());
  }
  RTCIntersectContext c;
  rtcInitIntersectContext(&c);
  if (!rays.empty()) rtcOccluded1M(scene.handle(), &c, rays.data(), unsigned(rays.size()), sizeof(RTCRay));
  visible.resize(uv.size());
  for (size_t k = 0; k < uv.size(); ++k) visible[k] = rays[k].tfar != -std::numeric_limits<float>::infinity();
}

void accumulate(const Vertex& v, int order, const Eigen::Vector2d& p, double weight, double* acc) {
  double u = p.x() + v.s, w = p.y() + v.u;
  u -= std::floor(u), w -= std::floor(w);
  const Eigen::Vector3d d = cosine_direction(u, w);
  const Eigen::Vector3d dir = (d.x() * v.t + d.y() * v.b + d.z() * v.n).normalized();
  double y[kMaxShOrder * kMaxShOrder];
  sh_eval(order, dir.x(), dir.y(), dir.z(), y);
  for (int c = 0; c < order * order; ++c) acc[c] -= M_PI * weight * y[c];
}

// The estimate from the given lattice of M points: t = t_u − (π/M) Σ_blocked y.
void uniform(const RayScene& scene, const Vertex& v, int order, const std::vector<Eigen::Vector2d>& uv, double* out) {
  const uint64_t M = uv.size();
  std::vector<char> vis;
  trace(scene, v, uv, vis);
  unshadowed_transfer(order, v.n, out);
  for (uint64_t q = 0; q < M; ++q)
    if (!vis[q]) accumulate(v, order, uv[q], 1.0 / double(M), out);
}

// A lattice's cells split level by level: value[j][q] is the visibility at point q of lattice j
// (−1: not traced there, the cell of level j − 1 holding it has the value), leaf[j][q] whether
// that cell is a leaf.
struct SplitTree {
  const Lattices& L;
  std::vector<std::vector<signed char>> value;
  std::vector<std::vector<char>> leaf;
  SplitTree(const Lattices& l, const std::vector<char>& level0, int levels) : L(l), value(size_t(levels) + 1), leaf(size_t(levels) + 1) {
    value[0].assign(level0.begin(), level0.end()), leaf[0].assign(L.base, 1);
  }
  signed char resolve(int j, uint64_t q) const {
    while (value[size_t(j)][q] < 0) {
      const uint64_t M = uint64_t(L.base) << j;
      q = (q & 1) ? ((q + M - L.partner[size_t(j) - 1]) % M) / 2 : q / 2;  // the cell of level j − 1 holding it
      --j;
    }
    return value[size_t(j)][q];
  }
  // Splits the leaves of level j that split(q) picks: traces their partners; returns their count.
  template <class Pick>
  uint64_t refine(const RayScene& scene, const Vertex& v, int j, Pick split_it) {
    const uint64_t M = uint64_t(L.base) << j, o = L.partner[size_t(j)];
    value[size_t(j) + 1].assign(2 * M, -1), leaf[size_t(j) + 1].assign(2 * M, 0);
    std::vector<uint64_t> split;
    for (uint64_t q = 0; q < M; ++q)
      if (leaf[size_t(j)][q] && split_it(q)) split.push_back(q);
    std::vector<Eigen::Vector2d> uv;
    for (uint64_t q : split) uv.push_back(L.point(j + 1, (2 * q + o) % (2 * M)));
    std::vector<char> vis;
    trace(scene, v, uv, vis);
    for (size_t k = 0; k < split.size(); ++k) {
      const uint64_t q = split[k], partner = (2 * q + o) % (2 * M);
      leaf[size_t(j)][q] = 0;
      value[size_t(j) + 1][2 * q] = value[size_t(j)][q], leaf[size_t(j) + 1][2 * q] = 1;
      value[size_t(j) + 1][partner] = vis[k], leaf[size_t(j) + 1][partner] = 1;
    }
    return split.size();
  }
  // t_u − π Σ over blocked leaves of area · y.
  void estimate(const Vertex& v, int order, double* out) const {
    unshadowed_transfer(order, v.n, out);
    for (size_t j = 0; j < leaf.size(); ++j) {
      const uint64_t M = uint64_t(L.base) << j;
      for (uint64_t q = 0; q < M; ++q)
        if (leaf[j][q] && value[j][q] == 0) accumulate(v, order, L.point(int(j), q), 1.0 / double(M), out);
    }
  }
};

// The level-0 lattice traced at v.
std::vector<char> first_level(const RayScene& scene, const Vertex& v, const Lattices& L) {
  std::vector<Eigen::Vector2d> uv;
  for (uint32_t q = 0; q < L.base; ++q) uv.push_back(L.point(0, q));
  std::vector<char> vis;
  trace(scene, v, uv, vis);
  return vis;
}

// Split where a cell's own point differs from a neighbour's. Returns rays traced.
uint64_t own(const RayScene& scene, const Vertex& v, int order, const Lattices& L, int levels, double* out) {
  SplitTree tree(L, first_level(scene, v, L), levels);
  uint64_t rays = L.base;
  for (int j = 0; j < levels; ++j) {
    const uint64_t M = uint64_t(L.base) << j;
    rays += tree.refine(scene, v, j, [&](uint64_t q) {
      const signed char mine = tree.value[size_t(j)][q];
      for (uint32_t m : L.near[size_t(j)])
        if (tree.resolve(j, (q + m) % M) != mine || tree.resolve(j, (q + M - m) % M) != mine) return true;
      return false;
    });
  }
  tree.estimate(v, order, out);
  return rays;
}

double torus_distance2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return wrapped2(a.x() - b.x(), a.y() - b.y()); }

// The shifted level-0 points whose visibility differs from a neighbour's: where a boundary is.
std::vector<Eigen::Vector2d> boundary_points(const Vertex& v, const Lattices& L, const std::vector<char>& vis) {
  std::vector<Eigen::Vector2d> out;
  const uint32_t M = L.base;
  for (uint32_t q = 0; q < M; ++q)
    for (uint32_t m : L.near[0])
      if (vis[(q + m) % M] != vis[q] || vis[(q + M - m) % M] != vis[q]) {
        const Eigen::Vector2d p = L.point(0, q) + Eigen::Vector2d(v.s, v.u);
        out.push_back(p - p.array().floor().matrix());
        break;
      }
  return out;
}

// Half A split where half B saw a boundary within rho (in the unit square), and B where A did:
// each half's partition is independent of its own samples. Returns rays; out = the halves' mean.
uint64_t cross(const RayScene& scene, const Vertex& va, const Vertex& vb, int order, const Lattices& L, int levels, double rho,
               double* out) {
  const std::vector<char> vis[2] = {first_level(scene, va, L), first_level(scene, vb, L)};
  const std::vector<Eigen::Vector2d> seen[2] = {boundary_points(va, L, vis[0]), boundary_points(vb, L, vis[1])};
  uint64_t rays = 2ull * L.base;
  const int K = order * order;
  std::fill(out, out + K, 0.0);
  for (int h = 0; h < 2; ++h) {
    const Vertex& v = h ? vb : va;
    SplitTree tree(L, vis[h], levels);
    for (int j = 0; j < levels; ++j)
      rays += tree.refine(scene, v, j, [&](uint64_t q) {
        Eigen::Vector2d p = L.point(j, q) + Eigen::Vector2d(v.s, v.u);
        p -= p.array().floor().matrix();
        for (const Eigen::Vector2d& b : seen[1 - h])
          if (torus_distance2(p, b) < rho * rho) return true;
        return false;
      });
    std::vector<double> t(static_cast<size_t>(K), 0.0);
    tree.estimate(v, order, t.data());
    for (int c = 0; c < K; ++c) out[c] += 0.5 * t[size_t(c)];
  }
  return rays;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return std::fprintf(stderr, "usage: adaptive_lattice SCENE [ORDER] [VERTICES] [REF_LEVELS]\n"), 2;
  const int order = argc > 2 ? std::atoi(argv[2]) : 4, count = argc > 3 ? std::atoi(argv[3]) : 2000;
  const int ref_levels = argc > 4 ? std::atoi(argv[4]) : 8;  // 256·2^8 = 65536
  const Mesh mesh = load_mesh(argv[1]);
  const RayScene scene(mesh.positions, position_triangles(mesh));
  const int K = order * order;
  std::vector<Vertex> verts;
  for (const BenchVertex& b : random_vertices(mesh, scene, count)) verts.push_back({b, 0, 0});
  // Reference at seed-independent shifts.
  std::vector<std::vector<double>> ref(verts.size(), std::vector<double>(size_t(K)));
  const Lattices refL(256, ref_levels);
  Rng rs(77, 0);
  for (size_t i = 0; i < verts.size(); ++i) {
    Vertex v = verts[i];
    v.s = rs.uniform(), v.u = rs.uniform();
    uniform(scene, v, order, refL.points(ref_levels), ref[i].data());
  }
  const int reps = 4;  // shifts per vertex, to average the error
  auto run_cross = [&](uint32_t base, int levels, double rho_cells) {
    const Lattices L(base, levels);
    const double rho = rho_cells / std::sqrt(double(base));
    double err = 0, rays = 0;
    std::vector<double> t(static_cast<size_t>(K), 0.0);
    for (int r = 0; r < reps; ++r) {
      Rng rng(1000 + uint64_t(r), 0);
      for (size_t i = 0; i < verts.size(); ++i) {
        Vertex a = verts[i], b = verts[i];
        a.s = rng.uniform(), a.u = rng.uniform(), b.s = rng.uniform(), b.u = rng.uniform();
        rays += double(cross(scene, a, b, order, L, levels, rho, t.data()));
        for (int c = 0; c < K; ++c) err += (t[size_t(c)] - ref[i][size_t(c)]) * (t[size_t(c)] - ref[i][size_t(c)]);
      }
    }
    const double n = double(reps) * double(verts.size());
    if (rho_cells == 0) std::printf("| two halves | 2 x %u | - | %.1f | %.4g |\n", base, rays / n, err / n);
    else std::printf("| cross, rho %.1f | 2 x %u | %d | %.1f | %.4g |\n", rho_cells, base, levels, rays / n, err / n);
    std::fflush(stdout);
  };
  auto run = [&](const char* name, uint32_t base, int levels, bool adapt) {
    const Lattices L(base, levels);
    double err = 0, rays = 0;
    std::vector<double> t(static_cast<size_t>(K), 0.0);
    for (int r = 0; r < reps; ++r) {
      Rng rng(1000 + uint64_t(r), 0);
      for (size_t i = 0; i < verts.size(); ++i) {
        Vertex v = verts[i];
        v.s = rng.uniform(), v.u = rng.uniform();
        if (adapt) rays += double(own(scene, v, order, L, levels, t.data()));
        else uniform(scene, v, order, L.points(levels), t.data()), rays += double(base << levels);
        for (int c = 0; c < K; ++c) err += (t[size_t(c)] - ref[i][size_t(c)]) * (t[size_t(c)] - ref[i][size_t(c)]);
      }
    }
    const double n = double(reps) * double(verts.size());
    std::printf("| %s | %u | %d | %.1f | %.4g |\n", name, base, levels, rays / n, err / n);
    std::fflush(stdout);
  };
  std::printf("%s: %zu vertices, order %d, reference %d rays\n\n", argv[1], verts.size(), order, 256 << ref_levels);
  std::printf("| estimator | base | levels | mean rays | mean squared error |\n|---|---:|---:|---:|---:|\n");
  for (int l = 0; l <= 4; ++l) run("uniform", 128, l, false);
  // Two halves of HALF (default 512) reached by doubling smaller lattices, as later rounds do (vertex_top_up):
  // the rank-1 doublings above against the library's (doubling_lattice).
  const uint32_t half = std::getenv("HALF") ? uint32_t(std::atoi(std::getenv("HALF"))) : 512u;
  for (uint32_t b : {512u, 256u, 128u, 64u, 32u, 16u})
    for (int library = 0; library < 2 && b <= half; ++library) {
      int d = 0;
      while ((b << d) < half) ++d;
      std::vector<Eigen::Vector2d> uv = Lattices(b, d).points(d);
      if (library) {
        const DoublingLattice l = doubling_lattice(b, d);
        for (uint32_t n = 0; n < half; ++n) uv[n] = doubling_lattice_point(n, l);
      }
      double err = 0;
      std::vector<double> t(static_cast<size_t>(K), 0.0), h(static_cast<size_t>(K), 0.0);
      for (int r = 0; r < reps; ++r) {
        Rng rng(1000 + uint64_t(r), 0);
        for (size_t i = 0; i < verts.size(); ++i) {
          std::fill(t.begin(), t.end(), 0.0);
          for (int half = 0; half < 2; ++half) {
            Vertex v = verts[i];
            v.s = rng.uniform(), v.u = rng.uniform();
            uniform(scene, v, order, uv, h.data());
            for (int c = 0; c < K; ++c) t[size_t(c)] += 0.5 * h[size_t(c)];
          }
          for (int c = 0; c < K; ++c) err += (t[size_t(c)] - ref[i][size_t(c)]) * (t[size_t(c)] - ref[i][size_t(c)]);
        }
      }
      std::printf("| two halves of %u doubled %d times, %s | 2 x %u | %d | %u | %.4g |\n", b, d, library ? "three-way" : "rank-1", b, d, 2 * half,
                  err / (double(reps) * double(verts.size())));
      if (d == 0) break;  // no doubling: the same lattice
    }
  if (std::getenv("OWN"))
    for (uint32_t b : {64u, 128u, 256u})
      for (int l = 1; l <= 4; ++l) run("own", b, l, true);
  for (uint32_t b : {64u, 128u, 256u, 512u}) run_cross(b, 0, 0);  // two uniform halves: the production estimator's shape
  for (double rho : {1.0, 1.5})
    for (uint32_t b : {64u, 128u})
      for (int l = 1; l <= 4; ++l) run_cross(b, l, rho);
  return 0;
}
