// Interreflection by the standard recursion. The light leaving a diffuse point h towards p is
// (ρ/π) Σ_i l_i t_i(h), so p receives, through every direction the mesh blocks, the transfer of
// the point it sees: a bounce adds (ρ/π) ∫ (1 − V) t(h) max(n·ω, 0) dω to p's transfer, and the
// asset's relighting rule, radiance = ρ/π Σ l_i t_i, stays what it is. Each pass bounces only the
// previous pass's addition, so the passes are the terms of the Neumann series and their sum is
// the light after that many bounces; each is at most ρ times the last where the mesh encloses p,
// so the series converges geometrically.
//
// Directions are cosine-distributed (pdf cos/π), so each pass's estimate is (ρ/R) times the sum of
// t_{k−1} over the rays that hit a front face. They come from a rank-1 lattice shifted per vertex
// (the vertex's own stream of a seed of their own, independent of the direct transfer's rays) and
// are the same in every pass, which is what lets the hits be kept: a hit is the face and its two
// barycentrics, 12 bytes, so R = 256 rays cost 3 KiB a vertex. Without the cache every pass
// traces the same rays again and finds the same hits.
//
// gather_bounce is one such pass at points that are not vertices (the bake's fit samples): the
// same rays, the same rule at the hit, so at a vertex's own position and stream it is that
// vertex's pass exactly.
#include "prtsub/prt/interreflection.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "prtsub/prt/evaluate.h"
#include "prtsub/prt/parallel.h"
#include "prtsub/prt/sampling.h"
#include "prtsub/prt/vertex_top_up.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {

BounceCache parse_bounce_cache(const std::string& name) {
  if (name == "auto") return BounceCache::Auto;
  if (name == "on") return BounceCache::On;
  if (name == "off") return BounceCache::Off;
  throw InputError("unknown bounce cache '" + name + "' (auto, on, off)");
}

const char* bounce_cache_name(BounceCache c) { return c == BounceCache::Auto ? "auto" : c == BounceCache::On ? "on" : "off"; }

namespace {

struct Hit {
  int32_t face;  // -1: escaped, or a back face (contributes nothing)
  float u, v;
};

constexpr uint64_t kBounceSeed = 0xB0B0CE5EEDull;

// The R rays of a point (normal n, leaving along `away`, lattice shifted by its stream), in ray
// order, as one stream for rtcIntersect1M (they share an origin), and their directions.
void point_rays(const RayScene& scene, const Eigen::Vector3d& point, const Eigen::Vector3d& n, const Eigen::Vector3d& away,
                const LatticeTable& lattice, uint32_t R, uint64_t seed, uint64_t stream, std::vector<RTCRayHit>& rays,
                std::vector<Eigen::Vector3d>& dirs) {
  Eigen::Vector3d t, b;
  tangent_frame(n, t, b);
  const Eigen::Vector3f local = scene.to_local(point);
  const Eigen::Vector3f origin = local + scene.ray_offset(local) * away.cast<float>();
  Rng rng(mix64(seed ^ kBounceSeed), stream);
  const double shift_u = rng.uniform(), shift_v = rng.uniform();
  const LatticeShift shift(shift_u, shift_v);
  rays.resize(R), dirs.resize(R);
  for (uint32_t k = 0; k < R; ++k) {
    const Eigen::Vector3d d = shifted_direction(lattice, k, shift);
    dirs[k] = (d.x() * t + d.y() * b + d.z() * n).normalized();
    init_occlusion_ray(rays[k].ray, origin, dirs[k].cast<float>());
    rays[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rays[k].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  }
}

void vertex_rays(const Mesh& mesh, const RayScene& scene, const RowMatrixX3d& offsets, const LatticeTable& lattice,
                 uint32_t R, uint64_t seed, uint32_t i, std::vector<RTCRayHit>& rays, std::vector<Eigen::Vector3d>& dirs) {
  point_rays(scene, mesh.point(i), mesh.normals.row(i).transpose(), offsets.row(i).transpose(), lattice, R, seed, i, rays, dirs);
}

void intersect(const RayScene& scene, std::vector<RTCRayHit>& rays) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect1M(scene.handle(), &context, rays.data(), static_cast<unsigned>(rays.size()), sizeof(RTCRayHit));
}

// The hits of the rays, in ray order: a back face is no hit (black).
void classify(const std::vector<RTCRayHit>& rays, const std::vector<Eigen::Vector3d>& dirs, const std::vector<Eigen::Vector3d>& face_normal,
              Hit* out) {
  for (size_t k = 0; k < rays.size(); ++k) {
    const RTCHit& hit = rays[k].hit;
    Hit& h = out[k];
    h.face = -1, h.u = h.v = 0;
    if (hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
    if (dirs[k].dot(face_normal[hit.primID]) >= 0) continue;  // the triangle's back: black
    h.face = static_cast<int32_t>(hit.primID), h.u = hit.u, h.v = hit.v;
  }
}

// The R hits of vertex i, in ray order.
void trace_vertex(const Mesh& mesh, const RayScene& scene, const RowMatrixX3d& offsets, const std::vector<Eigen::Vector3d>& face_normal,
                  const LatticeTable& lattice, uint32_t R, uint64_t seed, uint32_t i, Hit* out) {
  thread_local std::vector<RTCRayHit> rays;
  thread_local std::vector<Eigen::Vector3d> dirs;
  vertex_rays(mesh, scene, offsets, lattice, R, seed, i, rays, dirs);
  intersect(scene, rays);
  classify(rays, dirs, face_normal, out);
}

std::vector<Eigen::Vector3d> face_normals(const Mesh& mesh) {
  std::vector<Eigen::Vector3d> face_normal(mesh.num_faces());
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    const Triangle& t = mesh.triangles[f];
    face_normal[f] = (mesh.point(t[1]) - mesh.point(t[0])).cross(mesh.point(t[2]) - mesh.point(t[0]));
  }
  return face_normal;
}

// (albedo/R) Σ over the hits of `values` interpolated in the hit triangle; with a coloured
// albedo, each channel's block times that channel's albedo at the hit.
void gather(const Mesh& mesh, const RowMatrixXd& values, const Hit* hits, uint32_t R, const BounceOptions& o, Eigen::RowVectorXd& sum) {
  sum.setZero();
  const Eigen::Index K = values.cols() / 3;
  for (uint32_t k = 0; k < R; ++k) {
    const Hit& h = hits[k];
    if (h.face < 0) continue;
    const Triangle& t = mesh.triangles[static_cast<size_t>(h.face)];
    const double w1 = h.u, w2 = h.v, w0 = 1.0 - w1 - w2;
    if (!o.colour) {
      sum += w0 * values.row(t[0]) + w1 * values.row(t[1]) + w2 * values.row(t[2]);
      continue;
    }
    const Eigen::Vector3d rho = o.colour->at(static_cast<uint32_t>(h.face), w1, w2);
    for (int c = 0; c < 3; ++c)
      sum.segment(c * K, K) +=
          rho[c] * (w0 * values.row(t[0]).segment(c * K, K) + w1 * values.row(t[1]).segment(c * K, K) + w2 * values.row(t[2]).segment(c * K, K));
  }
  sum *= (o.colour ? 1.0 : o.albedo) / R;
}

void check_colour(const Mesh& mesh, const RowMatrixXd& values, const BounceOptions& o, const char* what) {
  if (!o.colour) return;
  if (static_cast<size_t>(o.colour->vertices().rows()) != mesh.num_vertices())
    throw InputError(std::string(what) + ": the albedo is for another mesh");
  if (values.cols() % 3 != 0) throw InputError(std::string(what) + ": RGB values need three blocks of coefficients");
}

void check_bounce_options(const BounceOptions& o) {
  if (o.bounces < 0 || o.bounces > 64) throw InputError("bounces must be between 0 and 64, got " + std::to_string(o.bounces));
  if (!(o.albedo >= 0 && o.albedo <= 1)) throw InputError("albedo must be between 0 and 1, got " + std::to_string(o.albedo));
  if (o.rays < 1 || o.rays > (1 << 16)) throw InputError("bounce rays per vertex must be between 1 and 65536, got " + std::to_string(o.rays));
}

}  // namespace

RowMatrixXd interreflected_transfer(const Mesh& mesh, const RayScene& scene, const RowMatrixXd& direct, const BounceOptions& o,
                                    BounceStats* stats, RowMatrixXd* before_last) {
  check_bounce_options(o);
  const size_t V = mesh.num_vertices();
  if (static_cast<size_t>(direct.rows()) != V) throw InputError("interreflection: the direct transfer has the wrong number of rows");
  Stopwatch clock;
  BounceStats s;
  // Colour: every channel starts from the same direct transfer and bounces by its own albedo.
  RowMatrixXd total = o.colour ? RowMatrixXd(direct.replicate(1, 3)) : direct;
  check_colour(mesh, total, o, "interreflection");
  if (before_last) *before_last = total;
  if (o.bounces == 0 || V == 0) {
    if (stats) *stats = s;
    return total;
  }
  const auto R = static_cast<uint32_t>(o.rays);
  const LatticeTable lattice = lattice_table(0, R, doubling_lattice(R, 0));
  const RowMatrixX3d offsets = vertex_offset_directions(mesh);
  const std::vector<Eigen::Vector3d> face_normal = face_normals(mesh);
  const double cache_mib = double(V) * R * sizeof(Hit) / (1024.0 * 1024.0);
  s.cached = o.cache == BounceCache::On || (o.cache == BounceCache::Auto && cache_mib <= o.cache_limit_mib);
  s.cache_mib = s.cached ? cache_mib : 0;
  std::vector<Hit> cache(s.cached ? V * R : 0);
  if (s.cached) {
    parallel_range<size_t>(V, o.threads, 16, [&](const tbb::blocked_range<size_t>& range) {
      for (size_t i = range.begin(); i != range.end(); ++i)
        trace_vertex(mesh, scene, offsets, face_normal, lattice, R, o.seed, static_cast<uint32_t>(i), &cache[i * R]);
    });
    scene.check("tracing bounce rays");
    s.rays += uint64_t(V) * R;
  }

  const std::vector<double> area = vertex_areas(mesh);
  double area_total = 0;
  for (double a : area) area_total += a;
  const double unit = unshadowed_norm(static_cast<int>(std::lround(std::sqrt(static_cast<double>(direct.cols())))));
  const Eigen::Index K = total.cols();
  const double channels = o.colour ? 3 : 1;  // the change is the RMS over channels
  RowMatrixXd previous = total, next(direct.rows(), K);
  const int max_passes = o.until_converged ? std::max(o.bounces, 1) : o.bounces;
  for (int pass = 1; pass <= max_passes; ++pass) {
    parallel_range<size_t>(V, o.threads, 16, [&](const tbb::blocked_range<size_t>& range) {
      std::vector<Hit> own(s.cached ? 0 : R);
      Eigen::RowVectorXd sum(K);
      for (size_t i = range.begin(); i != range.end(); ++i) {
        const Hit* hits = s.cached ? &cache[i * R] : own.data();
        if (!s.cached) trace_vertex(mesh, scene, offsets, face_normal, lattice, R, o.seed, static_cast<uint32_t>(i), own.data());
        gather(mesh, previous, hits, R, o, sum);
        next.row(static_cast<Eigen::Index>(i)) = sum;
      }
    });
    if (!s.cached) scene.check("tracing bounce rays"), s.rays += uint64_t(V) * R;
    if (before_last) *before_last = total;
    total += next;
    double change2 = 0;
    for (size_t i = 0; i < V; ++i) change2 += area[i] * next.row(static_cast<Eigen::Index>(i)).squaredNorm();
    s.change_percent.push_back(100 * std::sqrt(change2 / channels / std::max(area_total, 1e-300)) / unit);
    s.passes = pass;
    std::swap(previous, next);
    if (o.until_converged && s.change_percent.back() < o.noise_percent) break;
  }
  if (!total.allFinite()) throw InputError("interreflection: the transfer became non-finite");
  s.seconds = clock.total();
  if (stats) *stats = s;
  return total;
}

RowMatrixXd gather_bounce(const Mesh& mesh, const RayScene& scene, const RowMatrixXd& values, const RowMatrixX3d& points,
                          const RowMatrixX3d& normals, const RowMatrixX3d& offsets, const BounceOptions& o, TransferStats* stats) {
  check_bounce_options(o);
  if (static_cast<size_t>(values.rows()) != mesh.num_vertices()) throw InputError("gather: the values have the wrong number of rows");
  if (points.rows() != normals.rows() || points.rows() != offsets.rows()) throw InputError("gather: points, normals and offsets differ in count");
  check_colour(mesh, values, o, "gather");
  const Stopwatch clock;
  const auto R = static_cast<uint32_t>(o.rays);
  const LatticeTable lattice = lattice_table(0, R, doubling_lattice(R, 0));
  const std::vector<Eigen::Vector3d> face_normal = face_normals(mesh);
  RowMatrixXd out(points.rows(), values.cols());
  parallel_range<Eigen::Index>(points.rows(), o.threads, 16, [&](const tbb::blocked_range<Eigen::Index>& range) {
    thread_local std::vector<RTCRayHit> rays;
    thread_local std::vector<Eigen::Vector3d> dirs;
    std::vector<Hit> hits(R);
    Eigen::RowVectorXd sum(values.cols());
    for (Eigen::Index i = range.begin(); i != range.end(); ++i) {
      point_rays(scene, points.row(i).transpose(), normals.row(i).transpose(), offsets.row(i).transpose(), lattice, R, o.seed,
                 static_cast<uint64_t>(i), rays, dirs);
      intersect(scene, rays);
      classify(rays, dirs, face_normal, hits.data());
      gather(mesh, values, hits.data(), R, o, sum);
      out.row(i) = sum;
    }
  });
  scene.check("gathering a bounce");
  if (stats) stats->rays = uint64_t(points.rows()) * R, stats->seconds = clock.total();
  return out;
}

// The passes' noise, before they run. All B passes read the same R rays per vertex. Two gathers
// of the direct light at a systematic subset of the vertices, each with rays of its own seed,
// differ by twice the variance of pass 1's estimate; a column of ones gathered alongside gives
// each vertex's ρh, h its fraction of rays that hit a front face. Later passes bounce the same
// rays' values again, each about ρh of the last where the surroundings look like the vertex's
// own (exact inside a uniformly lit bowl), and the noise of every vertex's passes travels into
// its neighbours' next passes: so the sum's variance is taken as pass 1's times
// S² = (Σ_{k<B} (ρh)^k)², which holds the propagated noise and so stays above the passes'
// measured noise: 1.2-2.3× of it on five shared interiors (ScenesBounceNoise). The area-weighted
// mean, halved as interpolation spreads it (reach_target's ½), per channel. (Tried first: the
// even and odd rays of each vertex's own lattice, which overstate it, since the two halves of
// one shifted lattice are not independent; and one gather of what the last pass bounced, without
// S, which leaves out the noise the passes carry from vertex to vertex, and fell below it.)
double bounce_noise(const Mesh& mesh, const RayScene& scene, const RowMatrixXd& direct, const BounceOptions& bounce, size_t points,
                    uint64_t* rays) {
  check_bounce_options(bounce);
  if (static_cast<size_t>(direct.rows()) != mesh.num_vertices()) throw InputError("bounce noise: the direct transfer has the wrong number of rows");
  if (bounce.bounces == 0 || mesh.num_vertices() == 0) return 0;
  const PilotVertices pilot = pilot_vertices(mesh, points);
  const std::vector<size_t>& pick = pilot.index;
  const auto n = static_cast<Eigen::Index>(pick.size());
  const RowMatrixX3d &p = pilot.points, &nrm = pilot.normals, &off = pilot.offsets;
  // Each channel's block: the direct light and a column of ones (colour scales each block by its ρ).
  const Eigen::Index K = direct.cols(), block = K + 1;
  const int channels = bounce.colour ? 3 : 1;
  RowMatrixXd one_block(direct.rows(), block);
  one_block << direct, Eigen::VectorXd::Ones(direct.rows());
  const RowMatrixXd gathered = one_block.replicate(1, channels);
  const std::vector<double> area = vertex_areas(mesh);
  BounceOptions b = bounce;
  TransferStats st;
  b.seed = mix64(bounce.seed ^ 0x9015E1ull);
  const RowMatrixXd g1 = gather_bounce(mesh, scene, gathered, p, nrm, off, b, &st);
  *rays += st.rays;
  b.seed = mix64(bounce.seed ^ 0x9015E2ull);
  const RowMatrixXd g2 = gather_bounce(mesh, scene, gathered, p, nrm, off, b, &st);
  *rays += st.rays;
  double sum = 0, weight = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double w = area[pick[static_cast<size_t>(k)]];
    for (int c = 0; c < channels; ++c) {
      const Eigen::Index at = c * block;
      const double rh = std::clamp((g1(k, at + K) + g2(k, at + K)) / 2, 0.0, 1.0);
      double term = 1, series = 0;
      for (int pass = 0; pass < bounce.bounces; ++pass) series += term, term *= rh;
      sum += w * series * series * (g1.row(k).segment(at, K) - g2.row(k).segment(at, K)).squaredNorm() / 2;
    }
    weight += w;
  }
  return sum / std::max(weight, 1e-300) / 2 / channels;
}

uint64_t bare_bounce_loop(const Mesh& mesh, const RayScene& scene, const BounceOptions& o, TransferStats* stats) {
  check_bounce_options(o);
  const auto R = static_cast<uint32_t>(o.rays);
  const LatticeTable lattice = lattice_table(0, R, doubling_lattice(R, 0));
  const RowMatrixX3d offsets = vertex_offset_directions(mesh);
  std::atomic<uint64_t> hits{0};
  const Stopwatch clock;
  parallel_range<size_t>(mesh.num_vertices(), o.threads, 16, [&](const tbb::blocked_range<size_t>& range) {
    thread_local std::vector<RTCRayHit> rays;
    thread_local std::vector<Eigen::Vector3d> dirs;
    uint64_t local = 0;
    for (size_t i = range.begin(); i != range.end(); ++i) {
      vertex_rays(mesh, scene, offsets, lattice, R, o.seed, static_cast<uint32_t>(i), rays, dirs);
      intersect(scene, rays);
      for (const RTCRayHit& r : rays) local += r.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    hits += local;
  });
  scene.check("tracing benchmark bounce rays");
  if (stats) stats->seconds = clock.total(), stats->rays = uint64_t(mesh.num_vertices()) * R;
  return hits.load();
}

}  // namespace prtsub
