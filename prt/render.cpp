// Rendering relit frames.
//
// One primary ray per pixel through the pixel centre:
//   x = (2(c+0.5)/W − 1)·tan(fov/2)·W/H,  y = (1 − 2(r+0.5)/H)·tan(fov/2),
//   direction = normalize(forward + x·right + y·trueUp),
//   right = normalize(forward × up), trueUp = right × forward.
// Gouraud shading computes each vertex's exit radiance once, (albedo/π)·l·t, and interpolates
// it with the hit's barycentrics. By linearity that equals interpolating t and then taking the
// dot product, which is what a vertex shader plus the rasteriser do. The reference computes
// transfer at every hit point, with the interpolated shading normal, through the same
// estimator as the bake.
#include "prtsub/prt/render.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "prtsub/prt/parallel.h"
#include "prtsub/prt/path_transfer.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
void check_camera(const Camera& cam) {
  const Eigen::Vector3d fwd = cam.target - cam.eye;
  if (!cam.eye.allFinite() || !cam.target.allFinite() || !cam.up.allFinite()) throw InputError("camera: non-finite eye, target or up");
  if (!(fwd.norm() > 0)) throw InputError("camera: eye and target coincide");
  if (!(cam.up.norm() > 0) || !(fwd.normalized().cross(cam.up.normalized()).norm() > 1e-6))
    throw InputError("camera: up is zero or parallel to the view direction");
  if (!(cam.fov_deg > 0 && cam.fov_deg < 180)) throw InputError("camera: fov must be between 0 and 180 degrees");
}

Camera auto_camera(const Bounds& b, int width, int height) {
  const Eigen::Vector3d ext = b.hi - b.lo;
  const bool z_up = ext.z() < 0.35 * std::min(ext.x(), ext.y());
  Camera cam;
  cam.up = z_up ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
  // Three-quarter view: from the front-right and above (about 25° of elevation).
  Eigen::Vector3d dir = z_up ? Eigen::Vector3d(0.6, -0.75, 0.45) : Eigen::Vector3d(0.6, 0.45, 0.75);
  cam.target = b.centre();
  cam.fov_deg = 40;
  const double radius = std::max(0.5 * b.diagonal(), 1e-30);
  const double half_v = 0.5 * cam.fov_deg * M_PI / 180;
  const double half_h = std::atan(std::tan(half_v) * width / std::max(height, 1));
  cam.eye = cam.target + dir.normalized() * (radius / std::sin(std::min(half_v, half_h)));
  return cam;
}

Eigen::Vector3d camera_ray(const Camera& cam, int c, int r, int W, int H) {
  const Eigen::Vector3d forward = (cam.target - cam.eye).normalized();
  const Eigen::Vector3d right = forward.cross(cam.up).normalized();
  const Eigen::Vector3d true_up = right.cross(forward);
  const double t = std::tan(0.5 * cam.fov_deg * M_PI / 180);
  const double x = (2 * (c + 0.5) / W - 1) * t * W / H, y = (1 - 2 * (r + 0.5) / H) * t;
  return (forward + x * right + y * true_up).normalized();
}

size_t SurfaceHits::covered() const {
  size_t n = 0;
  for (int32_t f : face) n += f >= 0;
  return n;
}

SurfaceHits trace_primary(const RayScene& scene, const Camera& cam, int W, int H, int threads) {
  if (W < 1 || H < 1 || W > 16384 || H > 16384) throw InputError("frame size " + std::to_string(W) + "x" + std::to_string(H) + ": width and height must be 1 to 16384");
  check_camera(cam);
  SurfaceHits hits;
  hits.width = W, hits.height = H;
  const size_t n = static_cast<size_t>(W) * H;
  hits.face.assign(n, -1);
  hits.u.assign(n, 0.f);
  hits.v.assign(n, 0.f);
  const Eigen::Vector3f origin = scene.to_local(cam.eye);
  parallel_range(H, threads, 4, [&](const tbb::blocked_range<int>& rows) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int r = rows.begin(); r != rows.end(); ++r)
      for (int c = 0; c < W; ++c) {
        RTCRayHit rh;
        init_occlusion_ray(rh.ray, origin, camera_ray(cam, c, r, W, H).cast<float>());
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene.handle(), &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        const size_t i = static_cast<size_t>(r) * W + c;
        hits.face[i] = static_cast<int32_t>(rh.hit.primID);
        hits.u[i] = rh.hit.u;
        hits.v[i] = rh.hit.v;
      }
  });
  scene.check("tracing primary rays");
  return hits;
}

RowMatrixX3d vertex_radiance(const RowMatrixXd& transfer, const ShLight& light, double albedo) {
  if (transfer_channels(transfer.cols()) != 3) {
    const Eigen::Index K = std::min<Eigen::Index>(transfer.cols(), light.coeffs.rows());
    return (albedo / M_PI) * (transfer.leftCols(K) * light.coeffs.topRows(K));
  }
  const Eigen::Index stride = transfer.cols() / 3, K = std::min<Eigen::Index>(stride, light.coeffs.rows());
  RowMatrixX3d out(transfer.rows(), 3);
  for (int c = 0; c < 3; ++c) out.col(c) = (albedo / M_PI) * (transfer.middleCols(c * stride, K) * light.coeffs.col(c).head(K));
  return out;
}

RowMatrixX3d vertex_radiance(const RowMatrixXd& transfer, const ShLight& light, const RowMatrixX3d& albedo) {
  if (albedo.rows() != transfer.rows()) throw InputError("radiance: the albedo has " + std::to_string(albedo.rows()) + " rows for " +
                                                         std::to_string(transfer.rows()) + " vertices");
  return vertex_radiance(transfer, light, 1.0).cwiseProduct(albedo);
}

Image shade_gouraud(const SurfaceHits& hits, const std::vector<Triangle>& triangles, const RowMatrixX3d& radiance) {
  Image img;
  img.width = hits.width, img.height = hits.height, img.channels = 4;
  img.pixels.assign(static_cast<size_t>(img.width) * img.height * 4, 0.f);
  for (size_t i = 0; i < hits.face.size(); ++i) {
    if (hits.face[i] < 0) continue;
    const Triangle& t = triangles[static_cast<size_t>(hits.face[i])];
    const double u = hits.u[i], v = hits.v[i], w = 1 - u - v;
    for (int c = 0; c < 3; ++c)
      img.pixels[4 * i + c] = static_cast<float>(w * radiance(t[0], c) + u * radiance(t[1], c) + v * radiance(t[2], c));
    img.pixels[4 * i + 3] = 1.f;
  }
  return img;
}

Eigen::Vector3d shading_point(const RowMatrixX3d& positions, const RowMatrixX3d& normals, const Triangle& t, double u,
                              double v) {
  const double w[3] = {1 - u - v, u, v};
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) p += w[k] * positions.row(t[k]).transpose();
  // Project p onto each corner's tangent plane and blend the projections (Hanika 2021): on a
  // convex patch this lifts the point towards the smooth surface the normals describe, so
  // rays inside the shading hemisphere no longer clip the neighbouring flat facets. A point
  // in a concave patch would move inwards; it keeps the flat point.
  Eigen::Vector3d q = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d pk = positions.row(t[k]).transpose(), nk = normals.row(t[k]).transpose();
    q += w[k] * (p - (p - pk).dot(nk) * nk);
  }
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) n += w[k] * normals.row(t[k]).transpose();
  return (q - p).dot(n) > 0 ? q : p;
}

void hit_points(const SurfaceHits& hits, const RowMatrixX3d& positions, const RowMatrixX3d& normals,
                const std::vector<Triangle>& triangles, RowMatrixX3d& points, RowMatrixX3d& point_normals) {
  const Eigen::Index n = static_cast<Eigen::Index>(hits.covered());
  points.resize(n, 3);
  point_normals.resize(n, 3);
  Eigen::Index k = 0;
  for (size_t i = 0; i < hits.face.size(); ++i) {
    if (hits.face[i] < 0) continue;
    const Triangle& t = triangles[static_cast<size_t>(hits.face[i])];
    const double u = hits.u[i], v = hits.v[i], w = 1 - u - v;
    points.row(k) = shading_point(positions, normals, t, u, v).transpose();
    Eigen::Vector3d nrm = (w * normals.row(t[0]) + u * normals.row(t[1]) + v * normals.row(t[2])).transpose();
    if (!(nrm.norm() > 1e-12)) {  // opposite normals cancelling: fall back to the face normal
      Eigen::Vector3d a = positions.row(t[0]), b = positions.row(t[1]), c = positions.row(t[2]);
      nrm = (b - a).cross(c - a);
      if (!(nrm.norm() > 0)) nrm = Eigen::Vector3d::UnitZ();
    }
    point_normals.row(k) = nrm.normalized().transpose();
    ++k;
  }
}

Image render_reference(const RayScene& scene, const SurfaceHits& hits, const RowMatrixX3d& positions,
                       const RowMatrixX3d& normals, const std::vector<Triangle>& triangles, const ShLight& light,
                       double albedo, const TransferOptions& options, TransferStats* stats, const ProgressFn& progress,
                       const PathOptions* bounced, const std::shared_ptr<const AlbedoField>& colour) {
  RowMatrixX3d points, point_normals;
  hit_points(hits, positions, normals, triangles, points, point_normals);
  RowMatrixXd t = shadowed_transfer(scene, points, point_normals, options, stats, progress);
  if (bounced && bounced->bounces > 0) {
    PathOptions p = *bounced;
    p.order = options.order;
    if (colour) p.colour = colour, t = t.replicate(1, 3).eval();
    TransferStats path_stats;
    t += path_traced_transfer(scene, PathSurface{positions, normals, triangles}, points, point_normals, p, nullptr, &path_stats, progress);
    if (stats) stats->rays += path_stats.rays, stats->seconds += path_stats.seconds;
  }
  RowMatrixX3d radiance = vertex_radiance(t, light, colour ? 1.0 : albedo);
  if (colour) {  // each pixel's own albedo, at its point of the face
    Eigen::Index k = 0;
    for (size_t i = 0; i < hits.face.size(); ++i)
      if (hits.face[i] >= 0) radiance.row(k) = radiance.row(k).cwiseProduct(colour->at(uint32_t(hits.face[i]), hits.u[i], hits.v[i]).transpose()), ++k;
  }
  Image img;
  img.width = hits.width, img.height = hits.height, img.channels = 4;
  img.pixels.assign(static_cast<size_t>(img.width) * img.height * 4, 0.f);
  Eigen::Index k = 0;
  for (size_t i = 0; i < hits.face.size(); ++i) {
    if (hits.face[i] < 0) continue;
    for (int c = 0; c < 3; ++c) img.pixels[4 * i + c] = static_cast<float>(radiance(k, c));
    img.pixels[4 * i + 3] = 1.f;
    ++k;
  }
  return img;
}

// Black -> purple -> red -> orange -> yellow, given as display (sRGB) colours.
const double kHeatStops[5][3] = {{0, 0, 0}, {0.35, 0.05, 0.55}, {0.85, 0.15, 0.3}, {0.98, 0.55, 0.05}, {1, 1, 0.6}};

ImageError image_error(const Image& a, const Image& b, Image* heat, double heat_scale) {
  if (a.width != b.width || a.height != b.height)
    throw InputError("images differ in size: " + std::to_string(a.width) + "x" + std::to_string(a.height) + " and " +
                     std::to_string(b.width) + "x" + std::to_string(b.height));
  if (a.channels < 3 || b.channels < 3) throw InputError("images need at least 3 channels (RGB)");
  const size_t n = static_cast<size_t>(a.width) * a.height;
  auto covered = [](const Image& img, size_t i) { return img.channels < 4 || img.pixels[i * img.channels + 3] > 0; };
  double sum_sq = 0, sum_b = 0, sum_b2 = 0, max_b = 0;
  ImageError e;
  std::vector<double> pixel_err(n, -1);
  for (size_t i = 0; i < n; ++i) {
    if (!covered(a, i) || !covered(b, i)) continue;
    double se = 0;
    for (int c = 0; c < 3; ++c) {
      double d = double(a.pixels[i * a.channels + c]) - b.pixels[i * b.channels + c];
      se += d * d;
      sum_b += b.pixels[i * b.channels + c];
      sum_b2 += double(b.pixels[i * b.channels + c]) * b.pixels[i * b.channels + c];
      max_b = std::max<double>(max_b, b.pixels[i * b.channels + c]);
    }
    sum_sq += se;
    pixel_err[i] = std::sqrt(se / 3);
    ++e.pixels;
  }
  if (e.pixels == 0) throw InputError("no pixel is covered in both images");
  const double count = 3.0 * static_cast<double>(e.pixels);
  const double rmse = std::sqrt(sum_sq / count), mean_b = sum_b / count;
  e.rmse_relative = mean_b > 0 ? rmse / mean_b : std::numeric_limits<double>::infinity();
  e.rmse_rms_relative = sum_b2 > 0 ? rmse / std::sqrt(sum_b2 / count) : std::numeric_limits<double>::infinity();
  e.psnr_db = rmse > 0 ? 20 * std::log10(max_b / rmse) : std::numeric_limits<double>::infinity();
  if (heat) {
    const auto& stops = kHeatStops;
    const double scale = std::max(heat_scale > 0 ? heat_scale * mean_b : 4 * e.rmse_relative * mean_b, 1e-30);
    heat->width = a.width, heat->height = a.height, heat->channels = 3;
    heat->pixels.assign(n * 3, 0.f);
    for (size_t i = 0; i < n; ++i) {
      double srgb[3] = {0.25, 0.25, 0.25};
      if (pixel_err[i] >= 0) {
        double x = std::min(pixel_err[i] / scale, 1.0) * 4;
        int k = std::min(static_cast<int>(x), 3);
        double f = x - k;
        for (int c = 0; c < 3; ++c) srgb[c] = stops[k][c] * (1 - f) + stops[k + 1][c] * f;
      }
      for (int c = 0; c < 3; ++c)  // store linear so the PNG encoder gives back these colours
        heat->pixels[i * 3 + c] = static_cast<float>(srgb_to_linear(srgb[c]));
    }
  }
  return e;
}

}  // namespace prtsub
