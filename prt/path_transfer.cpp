// Interreflected transfer by path tracing. With t_b the transfer after b bounces,
//     t_b(p) = ∫ V y cos⁺ dω + (ρ/π) ∫ (1 − V) t_{b−1}(h(p, ω)) cos⁺ dω,   t_0 = the direct transfer,
// where h is the first surface point along ω and a back face is black (t = 0): the recursion the
// bake's passes discretise on vertices. One cosine-distributed direction (pdf cos/π) makes the
// second integral ρ t_{b−1}(h) when it hits a front face, so a path estimates the bounced light
// without ever storing a value on the surface: nothing is interpolated, nothing comes from an
// asset. That is what makes it a reference for assets baked with bounces.
//
// The default estimator starts R paths at p, each with one direction; a path that hits a front
// face at h carries ρ and estimates t_{b−1}(h) there with two fresh directions: the direct part
// with the cross-fitted control variate of transfer.cpp at two rays (each ray's β is the other's
// visibility, so a fully open point is exact, a fully enclosed one exactly zero, and the
// estimate stays unbiased), and the bounced part by continuing from the first direction when it
// hits a front face and bounces are left. Its direct light at p itself is shadowed_transfer's.
// `plain` is the textbook estimator of all of t_B(p), no control variate and no split: an
// escaping direction adds π y(ω) times the path's weight. It is noisier, and it is what the
// default is checked against (path_transfer_test.cpp; the scenes' test on the Cornell box and
// house_on_site).
//
// Points on the surface are exact barycentric points of the hit triangle (not the ray's t), with
// the interpolated shading normal; rays leave them along the triangle's geometric normal by the
// scene's offset. Directions are iid, from each point's own stream, so the result and the
// variance (the paths' spread over their count, honest because they are independent) do not
// depend on the thread count.
#include "prtsub/prt/path_transfer.h"

#include <atomic>
#include <cmath>
#include <string>

#include "prtsub/prt/parallel.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {
namespace {

constexpr uint64_t kPathSeed = 0x9A7B5EEDull;

struct Tracer {
  const RayScene& scene;
  const PathSurface& s;
  const std::vector<Eigen::Vector3d>& face_normal;  // unit, by winding
  const PathOptions& o;
  uint64_t rays = 0;

  // A surface point the paths stand on.
  struct Point {
    Eigen::Vector3d n;     // shading normal
    Eigen::Vector3f from;  // ray origin, local
    Eigen::Vector3d rho;   // its albedo, per channel
  };

  Point start(const Eigen::Vector3d& p, const Eigen::Vector3d& n) const {
    const Eigen::Vector3f local = scene.to_local(p);
    return {n, local + scene.ray_offset(local) * n.cast<float>(), Eigen::Vector3d::Zero()};
  }

  // Direction ω around n, cosine-distributed.
  static Eigen::Vector3d direction(const Eigen::Vector3d& n, Rng& rng) {
    Eigen::Vector3d t, b;
    tangent_frame(n, t, b);
    const double u = rng.uniform(), v = rng.uniform();
    const Eigen::Vector3d d = cosine_direction(u, v);
    return (d.x() * t + d.y() * b + d.z() * n).normalized();
  }

  // The first surface along ω: 0 escaped, -1 a back face (black), 1 a front face (at `next`).
  int trace(const Point& at, const Eigen::Vector3d& w, Point& next) {
    RTCRayHit rh;
    init_occlusion_ray(rh.ray, at.from, w.cast<float>());
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect1(scene.handle(), &context, &rh);
    ++rays;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    const uint32_t f = rh.hit.primID;
    const Eigen::Vector3d& g = face_normal[f];
    if (!(w.dot(g) < 0)) return -1;
    const Triangle& tri = s.triangles[f];
    const double w1 = rh.hit.u, w2 = rh.hit.v, w0 = 1 - w1 - w2;
    const Eigen::Vector3d p = w0 * s.positions.row(tri[0]) + w1 * s.positions.row(tri[1]) + w2 * s.positions.row(tri[2]);
    Eigen::Vector3d n = w0 * s.normals.row(tri[0]) + w1 * s.normals.row(tri[1]) + w2 * s.normals.row(tri[2]);
    n = n.norm() > 1e-12 ? n.normalized() : g;
    const Eigen::Vector3f local = scene.to_local(p);
    next.n = n;
    next.from = local + scene.ray_offset(local) * g.cast<float>();
    next.rho = o.colour ? o.colour->at(f, w1, w2) : Eigen::Vector3d::Constant(o.albedo);
    return 1;
  }
};

}  // namespace

RowMatrixXd path_traced_transfer(const RayScene& scene, const PathSurface& surface, const RowMatrixX3d& points,
                                 const RowMatrixX3d& point_normals, const PathOptions& o, std::vector<double>* variance,
                                 TransferStats* stats, const ProgressFn& progress) {
  if (o.order < 1 || o.order > kMaxShOrder) throw InputError("paths: SH order must be between 1 and " + std::to_string(kMaxShOrder));
  if (o.paths < 1 || o.paths > (1 << 20)) throw InputError("paths per point must be between 1 and 1048576, got " + std::to_string(o.paths));
  if (o.bounces < 0 || o.bounces > 64) throw InputError("bounces must be between 0 and 64, got " + std::to_string(o.bounces));
  if (!(o.albedo >= 0 && o.albedo <= 1)) throw InputError("albedo must be between 0 and 1, got " + std::to_string(o.albedo));
  if (points.rows() != point_normals.rows()) throw InputError("paths: points and normals differ in count");
  if (surface.positions.rows() != surface.normals.rows()) throw InputError("paths: the surface's positions and normals differ in count");
  for (const Triangle& t : surface.triangles)
    for (uint32_t c : t)
      if (c >= surface.positions.rows()) throw InputError("paths: a triangle indexes past the surface's vertices");
  Stopwatch clock;
  std::vector<Eigen::Vector3d> face_normal(surface.triangles.size());
  for (size_t f = 0; f < surface.triangles.size(); ++f) {
    const Triangle& t = surface.triangles[f];
    const Eigen::Vector3d a = surface.positions.row(t[0]), b = surface.positions.row(t[1]), c = surface.positions.row(t[2]);
    const Eigen::Vector3d g = (b - a).cross(c - a);
    face_normal[f] = g.norm() > 0 ? Eigen::Vector3d(g.normalized()) : Eigen::Vector3d::Zero();
  }
  const int K = sh_count(o.order);
  const int C = o.colour ? 3 : 1;  // channels: each carries its own albedo along the path
  const Eigen::Index P = points.rows();
  RowMatrixXd out = RowMatrixXd::Zero(P, C * K);
  if (variance) variance->assign(static_cast<size_t>(P), 0.0);
  std::atomic<uint64_t> rays{0};
  parallel_range<Eigen::Index>(P, o.threads, 4, [&](const tbb::blocked_range<Eigen::Index>& range) {
    Tracer tr{scene, surface, face_normal, o};
    Eigen::VectorXd y(K), tu(K), value(C * K), sum(C * K), sum2(C * K);
    auto add = [&](const Eigen::Vector3d& weight, double scale, const Eigen::VectorXd& v) {
      for (int c = 0; c < C; ++c) value.segment(c * K, K) += (weight[c] * scale) * v;
    };
    // value += weight · t̂_b(at): the two-ray direct estimate, then the path goes on (or not).
    auto walk = [&](Tracer::Point at, int b, Eigen::Vector3d weight, Rng& rng) {
      for (;;) {
        const Eigen::Vector3d wa = Tracer::direction(at.n, rng), wb = Tracer::direction(at.n, rng);
        Tracer::Point next{}, unused{};
        const int ha = tr.trace(at, wa, next), hb = tr.trace(at, wb, unused);
        const int va = ha == 0, vb = hb == 0;  // visible
        if (va || vb) {
          unshadowed_transfer(o.order, at.n, tu.data());
          // Each ray's β is the other's visibility; (β t_u + π (V − β) y) / 2 per ray.
          add(weight, 0.5 * (vb + va), tu);
          if (va != vb) {
            sh_eval(o.order, wa.x(), wa.y(), wa.z(), y.data());
            add(weight, 0.5 * M_PI * (va - vb), y);
            sh_eval(o.order, wb.x(), wb.y(), wb.z(), y.data());
            add(weight, 0.5 * M_PI * (vb - va), y);
          }
        }
        if (ha != 1 || b == 0) return;
        weight = weight.cwiseProduct(next.rho), at = next, --b;
      }
    };
    for (Eigen::Index i = range.begin(); i != range.end(); ++i) {
      Rng rng(mix64(o.seed ^ kPathSeed), static_cast<uint64_t>(i));
      Eigen::Vector3d n = point_normals.row(i).transpose();
      n = n.norm() > 1e-12 ? n.normalized() : Eigen::Vector3d::UnitZ();
      const Tracer::Point p = tr.start(points.row(i).transpose(), n);
      sum.setZero(), sum2.setZero();
      for (int k = 0; k < o.paths; ++k) {
        value.setZero();
        if (o.plain) {
          // t̂_b(at) = π y(ω) if ω escapes, ρ t̂_{b−1}(h) on a front face, else 0.
          Tracer::Point at = p;
          Eigen::Vector3d weight = Eigen::Vector3d::Ones();
          for (int b = o.bounces;; --b) {
            const Eigen::Vector3d w = Tracer::direction(at.n, rng);
            Tracer::Point next{};
            const int h = tr.trace(at, w, next);
            if (h == 0) {
              sh_eval(o.order, w.x(), w.y(), w.z(), y.data());
              add(weight, M_PI, y);
            }
            if (h != 1 || b == 0) break;
            weight = weight.cwiseProduct(next.rho), at = next;
          }
        } else if (o.bounces > 0) {
          const Eigen::Vector3d w = Tracer::direction(n, rng);
          Tracer::Point h{};
          if (tr.trace(p, w, h) == 1) walk(h, o.bounces - 1, h.rho, rng);
        }
        sum += value;
        sum2 += value.cwiseProduct(value);
      }
      const double R = o.paths;
      out.row(i) = (sum / R).transpose();
      if (variance) (*variance)[static_cast<size_t>(i)] = o.paths > 1 ? (sum2 / R - (sum / R).cwiseProduct(sum / R)).sum() / (R - 1) : INFINITY;
    }
    rays += tr.rays;
    if (progress) progress(static_cast<size_t>(range.size()));
  });
  scene.check("tracing paths");
  if (!out.allFinite()) throw InputError("paths: the transfer became non-finite");
  if (stats) stats->rays = rays, stats->seconds = clock.total();
  return out;
}

}  // namespace prtsub
