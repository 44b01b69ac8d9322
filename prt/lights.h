// Distant lights in SH: environment maps, analytic lights, random lights, and rotation.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

//! A distant light L(ω) = Σ_i coeffs(i, c) y_i(ω) per colour channel c (RGB), in the
//! convention of docs/sh_convention.md.
struct ShLight {
  int order = 0;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> coeffs;  //!< #K by 3
  ShLight& operator+=(const ShLight& other);
};

//! A float image, channels interleaved, row 0 at the top.
struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
  float& at(int x, int y, int c) { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
};

//! Constant radiance `rgb` in every direction.
ShLight constant_light(int order, const Eigen::Vector3d& rgb);

//! A sky: on the upper hemisphere about `up` radiance goes linearly in (up·ω) from `horizon`
//! to `zenith`; below the horizon it is `ground`. Projected exactly (piecewise polynomial).
ShLight sky_light(int order, const Eigen::Vector3d& up, const Eigen::Vector3d& zenith,
                  const Eigen::Vector3d& horizon, const Eigen::Vector3d& ground);

//! The default sky of `--light sky`: up +y, blue zenith, pale horizon, dim ground.
ShLight default_sky(int order, const Eigen::Vector3d& up = Eigen::Vector3d::UnitY());

//! A sun: a disk of angular radius `radius_deg` about `direction` (towards the sun) with
//! constant radiance, scaled so that it delivers irradiance π·rgb at normal incidence (a white
//! surface facing it, unshadowed, then leaves radiance `rgb`, like constant light of 1).
//! radius 0 is a directional light.
ShLight sun_light(int order, const Eigen::Vector3d& direction, double radius_deg,
                  const Eigen::Vector3d& rgb = Eigen::Vector3d::Ones());

//! Seeded random light of unit power: Gaussian coefficients scaled to ‖l‖ = 1, the same in
//! every channel.
ShLight random_light(int order, uint64_t seed);

//! A light given by its coefficients (the same in every channel); missing ones are 0.
//! \throw InputError if more than order² are given
ShLight coefficients_light(int order, const std::vector<double>& coefficients);

//! Projects a lat-long (equirectangular) radiance map with exact per-texel solid angles.
//! Texel (column c, row r) of a W×H map covers u ∈ [c/W, (c+1)/W], v ∈ [r/H, (r+1)/H] with
//! θ = π v from +y and φ = 2π u, direction (sin θ cos φ, cos θ, −sin θ sin φ).
//! \throw InputError for an empty image or one with fewer than 3 channels (1 is grey)
ShLight environment_light(int order, const Image& latlong);

//! ∫ L(ω) f_i(ω) dω, i < count, for a lat-long radiance map, with environment_light's texel-exact
//! quadrature; `eval(direction, out)` writes the count values f_i(direction). #count by 3 (RGB).
//! \throw InputError as environment_light does
Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> integrate_latlong(const Image& latlong, int count,
                                                                           const std::function<void(const Eigen::Vector3d&, double*)>& eval);

//! Direction of lat-long coordinates (u, v) in [0,1]² (see environment_light).
Eigen::Vector3d latlong_direction(double u, double v);

//! The light after rotating the world by R: L'(ω) = L(R⁻¹ ω).
ShLight rotate_light(const ShLight& light, const Eigen::Matrix3d& rotation);

//! Block-diagonal SH rotation matrix (#K by #K): coefficients of f(R⁻¹ ω) are M · c.
Eigen::MatrixXd sh_rotation(int order, const Eigen::Matrix3d& rotation);

}  // namespace prtsub
