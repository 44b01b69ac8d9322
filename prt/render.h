// Relit frames: primary rays through a pinhole camera, shaded from per-vertex transfer
// (Gouraud, exactly what a GPU does with per-vertex PRT) or from transfer computed at every
// pixel (the per-pixel reference). Also the image error between two frames.
#pragma once

#include <string>

#include "prtsub/prt/lights.h"
#include "prtsub/prt/path_transfer.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/transfer.h"

namespace prtsub {

//! A pinhole camera; fov is the full vertical angle in degrees.
struct Camera {
  Eigen::Vector3d eye = Eigen::Vector3d(0, 0, 5), target = Eigen::Vector3d::Zero(), up = Eigen::Vector3d::UnitY();
  double fov_deg = 40;
};

//! Checks that a camera can form an image: eye and target apart, up not along the view, fov in
//! (0, 180). \throw InputError naming the problem
void check_camera(const Camera& camera);

//! A three-quarter view that frames the whole bounding box. The up axis is +z when the box is
//! much flatter in z than in x and y (a z-up site), else +y.
Camera auto_camera(const Bounds& bounds, int width, int height);

//! Unit direction of the primary ray through the centre of pixel (column c, row r from the top).
Eigen::Vector3d camera_ray(const Camera& camera, int c, int r, int width, int height);

//! What each pixel's primary ray hit: a face (or -1) and Embree's barycentrics (u, v), the
//! hit being (1−u−v)·v0 + u·v1 + v·v2.
struct SurfaceHits {
  int width = 0, height = 0;
  std::vector<int32_t> face;
  std::vector<float> u, v;
  size_t covered() const;
};

SurfaceHits trace_primary(const RayScene& scene, const Camera& camera, int width, int height, int threads = 0);

//! Exit radiance per vertex and channel, (albedo/π) Σ_i l_i t_i: #V by 3. RGB transfer (#V by
//! 3·N²) shades channel c with its own block: (albedo/π) Σ_i l_{c,i} t_{c,i}.
//! \pre light.order == order of transfer (or lower: missing coefficients are 0)
RowMatrixX3d vertex_radiance(const RowMatrixXd& transfer, const ShLight& light, double albedo);
//! The same with each vertex's own albedo (#V by 3, an asset's albedo_r/g/b).
RowMatrixX3d vertex_radiance(const RowMatrixXd& transfer, const ShLight& light, const RowMatrixX3d& albedo);

//! Gouraud frame: radiance interpolated barycentrically from the hit face's vertices. RGBA,
//! alpha 1 where a face was hit and 0 elsewhere.
Image shade_gouraud(const SurfaceHits& hits, const std::vector<Triangle>& triangles, const RowMatrixX3d& radiance);

//! The point transfer is estimated from for barycentrics (u, v) of triangle t: the flat point
//! lifted towards the smooth surface its vertex normals describe (on convex patches only).
Eigen::Vector3d shading_point(const RowMatrixX3d& positions, const RowMatrixX3d& normals, const Triangle& t, double u,
                              double v);

//! Shading points (see shading_point) and interpolated shading normals of covered pixels, in
//! pixel order.
void hit_points(const SurfaceHits& hits, const RowMatrixX3d& positions, const RowMatrixX3d& normals,
                const std::vector<Triangle>& triangles, RowMatrixX3d& points, RowMatrixX3d& point_normals);

//! The per-pixel reference: transfer computed at each hit point with `options`, then shaded.
//! With `bounced` (bounces > 0), the light of that many bounces is added at each pixel, traced
//! as paths through the same surface (path_transfer.h); its order is options.order. With
//! `colour` (a field over these triangles), each pixel is shaded with the albedo at its own
//! point, and the bounces carry it (bounced->colour is set to it).
Image render_reference(const RayScene& scene, const SurfaceHits& hits, const RowMatrixX3d& positions,
                       const RowMatrixX3d& normals, const std::vector<Triangle>& triangles, const ShLight& light,
                       double albedo, const TransferOptions& options, TransferStats* stats = nullptr,
                       const ProgressFn& progress = {}, const PathOptions* bounced = nullptr,
                       const std::shared_ptr<const AlbedoField>& colour = nullptr);

//! Error of image a against reference b over pixels covered in both (alpha > 0).
struct ImageError {
  double rmse_relative = 0;  //!< RMSE over covered pixels and RGB, divided by b's mean there
  //! ... divided by b's RMS there instead: the scale for lights that shade negative somewhere (a
  //! random SH light), where b's mean can be near 0 or below
  double rmse_rms_relative = 0;
  double psnr_db = 0;        //!< 20 log10(max of b / RMSE); infinite for identical images
  size_t pixels = 0;
};
//! \param heat if not null, receives a false-colour map of per-pixel error (0 black, yellow at
//!        the scale or more; uncovered pixels grey)
//! \param heat_scale the scale as a fraction of b's mean over the covered pixels, the same for
//!        every image compared with one b (so their maps share one absolute scale); 0: 4× this
//!        pair's RMSE (each map scaled to its own error)
//! \throw InputError if the sizes differ or nothing is covered in both
ImageError image_error(const Image& a, const Image& b, Image* heat = nullptr, double heat_scale = 0);

//! The heat map's colours, black to yellow, at 0, ¼, ½, ¾ and 1 of its scale (display sRGB).
extern const double kHeatStops[5][3];

}  // namespace prtsub
