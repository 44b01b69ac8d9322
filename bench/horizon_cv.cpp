// Prototype (issue 15, point 2): the horizon as a control variate. Per vertex, M azimuths each
// find their horizon by d steps of bisection in u (cosine_direction's radial coordinate: u = 0 the
// normal, u = 1 the tangent plane), assuming what is blocked along an azimuth is everything below
// one elevation. Between azimuths the horizon H(w) is interpolated linearly, and g(u, w) = 1[u <
// H(w)] is a model of the visibility whose blocked integral C = ∫dw ∫_H^1 y du has no rays in it
// (Gauss–Legendre). A lattice of R rays at an independent shift then estimates what the model
// misses, ∫∫ (g − V) y: t = t_u − π (C + (1/R) Σ (g_k − V_k) y_k), unbiased for any H.
// Compared at equal rays (M·d + R) with two halves (the library's shape), one lattice and as many
// independent points, all by their mean squared error over random vertices against one lattice of
// 16,384 rays. The last two columns: the share of the residual lattice's rays that were blocked,
// and of those where the model was wrong (what the lattice is left to estimate).
// With WARP=1 it measures instead lattices warped in u to crowd their points below the least
// elevation anything blocks: with that u from the reference (an oracle), and as two halves whose
// second rounds are warped by the other half's first (what a bake could do).
// usage: [WARP=1] bash bench/cpp.sh BUILD horizon_cv SCENE [ORDER] [VERTICES]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/sh.h"
#include "prtsub/prt/transfer.h"
#include "prtsub/subdiv/mesh_io.h"
#include "prtsub/subdiv/random.h"
#include "random_vertices.h"

using namespace prtsub;

namespace {

// The residual lattice's rays: how many were blocked, and where the horizon model was wrong.
double g_blocked = 0, g_missed = 0, g_seen = 0;

struct Vertex : BenchVertex {
  double least = 1;  // the least u of a blocked ray of the reference
};

Eigen::Vector3d world(const Vertex& v, double u, double w) {
  const Eigen::Vector3d d = cosine_direction(u, w);
  return (d.x() * v.t + d.y() * v.b + d.z() * v.n).normalized();
}

// visible[k]: ray k (at (u, w)[k]) escapes.
std::vector<char> trace(const RayScene& scene, const Vertex& v, const std::vector<Eigen::Vector2d>& uw) {
  std::vector<RTCRay> rays(uw.size());
  for (size_t k = 0; k < uw.size(); ++k) init_occlusion_ray(rays[k], v.origin, world(v, uw[k].x(), uw[k].y()).cast<float>());
  RTCIntersectContext c;
  rtcInitIntersectContext(&c);
  if (!rays.empty()) rtcOccluded1M(scene.handle(), &c, rays.data(), unsigned(rays.size()), sizeof(RTCRay));
  std::vector<char> vis(uw.size());
  for (size_t k = 0; k < uw.size(); ++k) vis[k] = rays[k].tfar != -std::numeric_limits<float>::infinity();
  return vis;
}

std::vector<Eigen::Vector2d> lattice(uint32_t n, double s, double t) {
  const DoublingLattice l = doubling_lattice(n, 0);
  std::vector<Eigen::Vector2d> uv(n);
  for (uint32_t k = 0; k < n; ++k) {
    Eigen::Vector2d p = doubling_lattice_point(k, l) + Eigen::Vector2d(s, t);
    uv[k] = p - p.array().floor().matrix();
  }
  return uv;
}

void add_y(int order, const Eigen::Vector3d& d, double w, double* acc) {
  double y[kMaxShOrder * kMaxShOrder];
  sh_eval(order, d.x(), d.y(), d.z(), y);
  for (int c = 0; c < order * order; ++c) acc[c] += w * y[c];
}

// Plain lattice (or independent points): t_u − (π/N) Σ_blocked y.
void plain(const RayScene& scene, const Vertex& v, int order, uint32_t n, Rng& rng, double* out, bool independent = false) {
  auto uv = lattice(n, rng.uniform(), rng.uniform());
  if (independent)
    for (auto& p : uv) p = {rng.uniform(), rng.uniform()};
  const auto vis = trace(scene, v, uv);
  unshadowed_transfer(order, v.n, out);
  for (size_t k = 0; k < uv.size(); ++k)
    if (!vis[k]) add_y(order, world(v, uv[k].x(), uv[k].y()), -M_PI / double(n), out);
}

// Gauss–Legendre nodes and weights on [0, 1].
void gauss(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(size_t(n), 0), w.assign(size_t(n), 0);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1, p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-15) break;
    }
    x[size_t(i)] = 0.5 * (1 - z), w[size_t(i)] = 1.0 / ((1 - z * z) * dp * dp);
  }
}

struct Horizon {
  std::vector<double> w, h;  // azimuths (sorted, in [0,1)) and their horizons in u
  double at(double x) const {
    const size_t M = w.size();
    // the segment [w_i, w_{i+1}) (periodic) holding x
    size_t i = size_t(std::upper_bound(w.begin(), w.end(), x) - w.begin());
    const size_t lo = (i + M - 1) % M, hi = i % M;
    double a = w[lo], b = w[hi];
    if (x < a) a -= 1;
    if (b <= a) b += 1;
    double xx = x;
    if (xx < a) xx += 1;
    const double f = (xx - a) / (b - a);
    return (1 - f) * h[lo] + f * h[hi];
  }
};

uint64_t horizon_cv(const RayScene& scene, const Vertex& v, int order, uint32_t M, int steps, uint32_t R, Rng& rng, double* out,
                    bool model_only = false) {
  Horizon H;
  const double a = rng.uniform();
  for (uint32_t i = 0; i < M; ++i) H.w.push_back((i + a) / M - std::floor((i + a) / M));
  std::sort(H.w.begin(), H.w.end());
  std::vector<double> lo(M, 0.0), hi(M, 1.0);
  for (int s = 0; s < steps; ++s) {
    std::vector<Eigen::Vector2d> uw(M);
    for (uint32_t i = 0; i < M; ++i) uw[i] = {0.5 * (lo[i] + hi[i]), H.w[i]};
    const auto vis = trace(scene, v, uw);
    for (uint32_t i = 0; i < M; ++i) (vis[i] ? lo[i] : hi[i]) = uw[i].x();
  }
  // Never blocked: open to the tangent plane; never seen: blocked from the normal down.
  for (uint32_t i = 0; i < M; ++i) H.h.push_back(hi[i] == 1.0 ? 1.0 : lo[i] == 0.0 ? 0.0 : 0.5 * (lo[i] + hi[i]));
  // C = ∫ dw ∫_{H(w)}^1 y du, per segment of w (Gauss–Legendre in w), u = 1 − s² inside.
  const int K = order * order;
  std::vector<double> C(size_t(K), 0.0), gx, gw, sx, sw;
  gauss(6, gx, gw), gauss(12, sx, sw);
  for (uint32_t i = 0; i < M; ++i) {
    double w0 = H.w[i], w1 = i + 1 < M ? H.w[i + 1] : H.w[0] + 1;
    for (size_t p = 0; p < gx.size(); ++p) {
      const double w = w0 + (w1 - w0) * gx[p], ww = (w1 - w0) * gw[p];
      const double wr = w - std::floor(w), hu = H.at(wr), smax = std::sqrt(std::max(0.0, 1 - hu));
      for (size_t q = 0; q < sx.size(); ++q) {
        const double s = smax * sx[q], u = 1 - s * s;  // du = 2s ds
        add_y(order, world(v, u, wr), ww * smax * sw[q] * 2 * s, C.data());
      }
    }
  }
  unshadowed_transfer(order, v.n, out);
  for (int c = 0; c < K; ++c) out[c] -= M_PI * C[size_t(c)];
  if (model_only) return uint64_t(M) * uint64_t(steps);
  const auto uv = lattice(R, rng.uniform(), rng.uniform());
  const auto vis = trace(scene, v, uv);
  for (size_t k = 0; k < uv.size(); ++k) {
    const double g = uv[k].x() < H.at(uv[k].y()) ? 1 : 0;
    const double d = g - (vis[k] ? 1 : 0);
    g_blocked += !vis[k], g_missed += d != 0, g_seen += 1;
    if (d != 0) add_y(order, world(v, uv[k].x(), uv[k].y()), -M_PI * d / double(R), out);
  }
  return uint64_t(M) * uint64_t(steps) + R;
}

// A lattice of n points warped in u: a share alpha·c of them in [0, c), the rest in [c, 1], each
// weighed by its cell's measure; adds −(π/n)·Σ_blocked weight·y to out, and returns the least u of a
// blocked point (1 if none).
double warped(const RayScene& scene, const Vertex& v, int order, uint32_t n, double c, double alpha, Rng& rng, double* out) {
  auto uv = lattice(n, rng.uniform(), rng.uniform());
  const double rho = alpha * c;  // the share of points in [0, c)
  for (auto& p : uv) {
    const double x = p.x();
    p.x() = x < rho ? x / rho * c : c + (x - rho) / (1 - rho) * (1 - c);
  }
  const auto vis = trace(scene, v, uv);
  double least = 1;
  for (size_t k = 0; k < uv.size(); ++k) {
    if (vis[k]) continue;
    const double u = uv[k].x(), w = u < c ? c / rho : (1 - c) / (1 - rho);
    least = std::min(least, u);
    add_y(order, world(v, u, uv[k].y()), -M_PI * w / double(n), out);
  }
  return least;
}

// Two halves, each a first round of n1 plain points and a second of n2 warped by the *other*
// half's first round: its least blocked u less a margin (so each half's warp is independent of
// its own rays, as the library's halves choose each other's β). Each half's rounds are averaged
// by their rays.
uint64_t warped_halves(const RayScene& scene, const Vertex& v, int order, uint32_t n1, uint32_t n2, double margin, double alpha,
                       Rng& rng, double* out) {
  const int K = order * order;
  std::vector<double> first[2], second[2];
  double least[2];
  for (int h = 0; h < 2; ++h) {
    first[h].assign(size_t(K), 0.0);
    least[h] = warped(scene, v, order, n1, 0, alpha, rng, first[h].data());
  }
  unshadowed_transfer(order, v.n, out);
  for (int h = 0; h < 2; ++h) {
    second[h].assign(size_t(K), 0.0);
    warped(scene, v, order, n2, std::max(0.0, least[1 - h] - margin), alpha, rng, second[h].data());
    const double a = double(n1) / double(n1 + n2);
    for (int c = 0; c < K; ++c) out[c] += 0.5 * (a * first[h][size_t(c)] + (1 - a) * second[h][size_t(c)]);
  }
  return 2ull * (n1 + n2);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return std::fprintf(stderr, "usage: horizon_cv SCENE [ORDER] [VERTICES]\n"), 2;
  const int order = argc > 2 ? std::atoi(argv[2]) : 4, count = argc > 3 ? std::atoi(argv[3]) : 500;
  const Mesh mesh = load_mesh(argv[1]);
  const RayScene scene(mesh.positions, position_triangles(mesh));
  const int K = order * order;
  std::vector<Vertex> verts;
  for (const BenchVertex& b : random_vertices(mesh, scene, count)) verts.push_back({b});
  std::vector<std::vector<double>> ref(verts.size(), std::vector<double>(size_t(K)));
  Rng rs(77, 0);
  for (size_t i = 0; i < verts.size(); ++i) plain(scene, verts[i], order, 16384, rs, ref[i].data());
  const int reps = 4;
  auto measure = [&](const char* name, auto&& estimate) {
    double err = 0, rays = 0;
    g_blocked = g_missed = g_seen = 0;
    std::vector<double> t(static_cast<size_t>(K));
    for (int r = 0; r < reps; ++r) {
      Rng rng(1000 + uint64_t(r), 0);
      for (size_t i = 0; i < verts.size(); ++i) {
        rays += double(estimate(verts[i], rng, t.data()));
        for (int c = 0; c < K; ++c) err += (t[size_t(c)] - ref[i][size_t(c)]) * (t[size_t(c)] - ref[i][size_t(c)]);
      }
    }
    const double n = double(reps) * double(verts.size());
    if (g_seen > 0) std::printf("| %s | %.0f | %.4g | %.4f | %.4f |\n", name, rays / n, err / n, g_blocked / g_seen, g_missed / g_seen);
    else std::printf("| %s | %.0f | %.4g | | |\n", name, rays / n, err / n);
    std::fflush(stdout);
  };
  std::printf("%s: %zu vertices, order %d, reference one lattice of 16384\n\n| estimator | rays | mean squared error | blocked | model wrong |\n|---|---:|---:|---:|---:|\n",
              argv[1], verts.size(), order);
  for (uint32_t n : {256u, 512u, 1024u}) {
    char name[64];
    std::snprintf(name, sizeof name, "two halves of %u", n / 2);
    measure(name, [&](const Vertex& v, Rng& rng, double* out) {
      std::vector<double> h(static_cast<size_t>(K));
      std::fill(out, out + K, 0.0);
      for (int k = 0; k < 2; ++k) {
        plain(scene, v, order, n / 2, rng, h.data());
        for (int c = 0; c < K; ++c) out[c] += 0.5 * h[size_t(c)];
      }
      return uint64_t(n);
    });
    std::snprintf(name, sizeof name, "%u independent points", n);
    measure(name, [&](const Vertex& v, Rng& rng, double* out) { return plain(scene, v, order, n, rng, out, true), uint64_t(n); });
    std::snprintf(name, sizeof name, "one lattice of %u", n);
    measure(name, [&](const Vertex& v, Rng& rng, double* out) { return plain(scene, v, order, n, rng, out), uint64_t(n); });
  }
  for (size_t i = 0; i < verts.size(); ++i) {
    std::vector<double> scratch(static_cast<size_t>(K), 0.0);
    Rng r2(78, 0);
    verts[i].least = warped(scene, verts[i], order, 16384, 0, 0.1, r2, scratch.data());
  }
  if (std::getenv("WARP")) {
    std::vector<double> least;
    for (const Vertex& v : verts) least.push_back(v.least);
    std::sort(least.begin(), least.end());
    std::printf("least blocked u of 16,384 rays, quartiles: %.3f %.3f %.3f\n\n", least[least.size() / 4], least[least.size() / 2],
                least[3 * least.size() / 4]);
    for (double alpha : {0.05, 0.2})
      for (uint32_t n : {256u, 512u}) {
        char name[96];
        std::snprintf(name, sizeof name, "oracle: one lattice of %u warped at the reference's least u, alpha %.2f", n, alpha);
        measure(name, [&](const Vertex& v, Rng& rng, double* out) {
          unshadowed_transfer(order, v.n, out);
          warped(scene, v, order, n, v.least, alpha, rng, out);
          return uint64_t(n);
        });
      }
    for (double margin : {0.05, 0.15})
      for (double alpha : {0.1, 0.3})
        for (uint32_t n : {256u, 512u}) {
          char name[96];
          std::snprintf(name, sizeof name, "warped halves 2 x (64 + %u), margin %.2f, alpha %.1f", n / 2 - 64, margin, alpha);
          measure(name, [&](const Vertex& v, Rng& rng, double* out) { return warped_halves(scene, v, order, 64, n / 2 - 64, margin, alpha, rng, out); });
        }
    return 0;
  }
  for (uint32_t M : {16u, 32u, 64u})
    for (int d : {4, 6}) {
      char name[96];
      std::snprintf(name, sizeof name, "horizon model alone, %u azimuths x %d steps (biased)", M, d);
      measure(name, [&](const Vertex& v, Rng& rng, double* out) { return horizon_cv(scene, v, order, M, d, 0, rng, out, true); });
      for (uint32_t R : {128u, 256u, 512u}) {
        std::snprintf(name, sizeof name, "horizon %u x %d + lattice %u", M, d, R);
        measure(name, [&](const Vertex& v, Rng& rng, double* out) { return horizon_cv(scene, v, order, M, d, R, rng, out); });
      }
    }
}
