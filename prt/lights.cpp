// Light projection and rotation.
//
// Zonal lights (sun caps, the sky about its up axis) project in closed form or by
// Gauss-Legendre quadrature that is exact for their piecewise-polynomial profiles: a function
// g(n·ω) about unit axis n has coefficients 2π ∫ g(t) P_l(t) dt · y_lm(n). Environment maps
// are summed texel by texel: each texel's radiance times the basis integrated over the texel,
// by a rule whose weights add up to its exact solid angle (φ1 − φ0)(cos θ0 − cos θ1).
//
// Rotation: y_l(R⁻¹ω) is a linear function of the band-l vector y_l(ω), so each band's
// (2l+1)×(2l+1) rotation matrix is found exactly by least squares over a fixed set of 4(2l+1)
// directions. It has no sign conventions to get wrong, and it is accurate to rounding for
// every order up to 10, as tests show against projecting the rotated function directly.
#include "prtsub/prt/lights.h"

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <sstream>

#include "prtsub/prt/sampling.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

using RowK3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

ShLight empty_light(int order) {
  if (order < 1 || order > kMaxShOrder) throw InputError("light: SH order must be 1 to 10, got " + std::to_string(order));
  ShLight l;
  l.order = order;
  l.coeffs = RowK3::Zero(sh_count(order), 3);
  return l;
}

// Legendre P_0..P_{n-1} at t.
void legendre(int n, double t, double* p) {
  p[0] = 1;
  if (n > 1) p[1] = t;
  for (int l = 2; l < n; ++l) p[l] = ((2 * l - 1) * t * p[l - 1] - (l - 1) * p[l - 2]) / l;
}

// Adds the zonal function g about `axis`, given by its Legendre moments m_l = 2π ∫ g P_l dt.
void add_zonal(ShLight& light, const Eigen::Vector3d& axis, const std::vector<Eigen::Vector3d>& moments) {
  Eigen::VectorXd y = sh_eval(light.order, axis.normalized());
  for (int l = 0; l < light.order; ++l)
    for (int m = -l; m <= l; ++m) light.coeffs.row(sh_index(l, m)) += y[sh_index(l, m)] * moments[static_cast<size_t>(l)].transpose();
}

// Fixed well-spread directions: a Fibonacci sphere.
std::vector<Eigen::Vector3d> spread_directions(int n) {
  std::vector<Eigen::Vector3d> d(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    double z = 1 - (2.0 * i + 1) / n, r = std::sqrt(std::max(0.0, 1 - z * z));
    double phi = 2 * M_PI * i * 0.6180339887498949;
    d[static_cast<size_t>(i)] = Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
  }
  return d;
}

}  // namespace

ShLight& ShLight::operator+=(const ShLight& other) {
  if (other.order != order) throw InputError("lights of different SH orders cannot be added");
  coeffs += other.coeffs;
  return *this;
}

ShLight constant_light(int order, const Eigen::Vector3d& rgb) {
  ShLight l = empty_light(order);
  l.coeffs.row(0) = (rgb * 2 * std::sqrt(M_PI)).transpose();  // ∫ y_0 dω = 4π · y_0 = 2√π
  return l;
}

ShLight sky_light(int order, const Eigen::Vector3d& up, const Eigen::Vector3d& zenith,
                  const Eigen::Vector3d& horizon, const Eigen::Vector3d& ground) {
  ShLight light = empty_light(order);
  // Profile g(t): ground for t < 0; horizon + (zenith - horizon) t for t ≥ 0. Each piece is a
  // polynomial of degree ≤ 1, times P_l of degree ≤ 9: 8 Gauss points per piece are exact.
  static const double x[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                              0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
  static const double w[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                              0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  std::vector<Eigen::Vector3d> moments(static_cast<size_t>(order), Eigen::Vector3d::Zero());
  double p[kMaxShOrder];
  for (int k = 0; k < 8; ++k) {
    double tl = 0.5 * (x[k] - 1), tu = 0.5 * (x[k] + 1);  // [-1,0] and [0,1]
    legendre(order, tl, p);
    for (int l = 0; l < order; ++l) moments[static_cast<size_t>(l)] += 2 * M_PI * 0.5 * w[k] * p[l] * ground;
    legendre(order, tu, p);
    for (int l = 0; l < order; ++l)
      moments[static_cast<size_t>(l)] += 2 * M_PI * 0.5 * w[k] * p[l] * (horizon + (zenith - horizon) * tu);
  }
  add_zonal(light, up, moments);
  return light;
}

ShLight default_sky(int order, const Eigen::Vector3d& up) {
  return sky_light(order, up, Eigen::Vector3d(0.35, 0.55, 1.0), Eigen::Vector3d(0.9, 0.9, 0.85),
                   Eigen::Vector3d(0.15, 0.13, 0.12));
}

ShLight sun_light(int order, const Eigen::Vector3d& direction, double radius_deg, const Eigen::Vector3d& rgb) {
  ShLight light = empty_light(order);
  if (!(direction.norm() > 0) || !direction.allFinite()) throw InputError("sun: direction must be a non-zero vector");
  if (!(radius_deg >= 0 && radius_deg <= 90)) throw InputError("sun: radius must be between 0 and 90 degrees");
  // A cap t ≥ cos α of radiance L_s with L_s · Ω = π (Ω = 2π(1 − cos α)): moments
  // 2π L_s ∫_{cos α}^1 P_l dt, with ∫_x^1 P_l = (P_{l-1}(x) − P_{l+1}(x))/(2l+1) for l ≥ 1.
  const double alpha = radius_deg * M_PI / 180, c = std::cos(alpha);
  double p[kMaxShOrder + 1];
  legendre(order + 1, c, p);
  std::vector<Eigen::Vector3d> moments(static_cast<size_t>(order));
  for (int l = 0; l < order; ++l) {
    double ratio;  // ∫_c^1 P_l dt / (1 − c), the cap average of P_l; → 1 as α → 0
    if (1 - c < 1e-12) {
      ratio = 1.0;
    } else {
      double integral = l == 0 ? 1 - c : (p[l - 1] - p[l + 1]) / (2 * l + 1);
      ratio = integral / (1 - c);
    }
    // 2π L_s (1−c) ratio = Ω L_s ratio = π ratio.
    moments[static_cast<size_t>(l)] = M_PI * ratio * rgb;
  }
  add_zonal(light, direction, moments);
  return light;
}

ShLight random_light(int order, uint64_t seed) {
  ShLight light = empty_light(order);
  Rng rng(seed, 0x5EED);
  Eigen::VectorXd c(sh_count(order));
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    // Box-Muller: Gaussian coefficients make the light's direction uniform on the sphere of
    // coefficient vectors.
    double u1 = std::max(rng.uniform(), 1e-300), u2 = rng.uniform();
    c[i] = std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  }
  c /= c.norm();
  for (int k = 0; k < 3; ++k) light.coeffs.col(k) = c;
  return light;
}

ShLight coefficients_light(int order, const std::vector<double>& coefficients) {
  ShLight light = empty_light(order);
  if (static_cast<int>(coefficients.size()) > sh_count(order))
    throw InputError("sh: " + std::to_string(coefficients.size()) + " coefficients given, but order " +
                     std::to_string(order) + " has " + std::to_string(sh_count(order)));
  for (size_t i = 0; i < coefficients.size(); ++i) light.coeffs.row(static_cast<Eigen::Index>(i)).setConstant(coefficients[i]);
  return light;
}

Eigen::Vector3d latlong_direction(double u, double v) {
  const double theta = M_PI * v, phi = 2 * M_PI * u;
  return {std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi)};
}

Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> integrate_latlong(const Image& img, int count,
                                                                           const std::function<void(const Eigen::Vector3d&, double*)>& eval) {
  if (img.width <= 0 || img.height <= 0 || img.channels <= 0) throw InputError("environment map: empty image");
  if (img.channels == 2) throw InputError("environment map: 2-channel images are not supported (use grey or RGB)");
  // Inside a texel: 4 Gauss-Legendre points in cos θ (exact for the polar polynomials of the
  // basis up to degree 7 per texel row) times 4 midpoints in φ; weights sum to the texel's
  // exact solid angle (2π/W)(cos θ0 − cos θ1).
  static const double gx[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
  static const double gw[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
  const int sub = 4;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> out = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>::Zero(count, 3);
  std::vector<double> y(static_cast<size_t>(count)), integral(static_cast<size_t>(count));
  for (int r = 0; r < img.height; ++r) {
    const double z0 = std::cos(M_PI * r / img.height), z1 = std::cos(M_PI * (r + 1) / img.height);
    const double zmid = 0.5 * (z0 + z1), zhalf = 0.5 * (z0 - z1);
    for (int col = 0; col < img.width; ++col) {
      std::fill(integral.begin(), integral.end(), 0.0);
      for (int a = 0; a < sub; ++a)
        for (int b = 0; b < 4; ++b) {
          const double phi = 2 * M_PI * (col + (a + 0.5) / sub) / img.width;
          const double ct = zmid + zhalf * gx[b], st = std::sqrt(std::max(0.0, 1 - ct * ct));
          const double w = (2 * M_PI / img.width / sub) * zhalf * gw[b];
          eval(Eigen::Vector3d(st * std::cos(phi), ct, -st * std::sin(phi)), y.data());
          for (int i = 0; i < count; ++i) integral[static_cast<size_t>(i)] += w * y[static_cast<size_t>(i)];
        }
      Eigen::Vector3d rgb;
      for (int c = 0; c < 3; ++c) rgb[c] = img.at(col, r, img.channels >= 3 ? c : 0);
      if (!rgb.allFinite()) throw InputError("environment map: texel (" + std::to_string(col) + ", " + std::to_string(r) + ") is not finite");
      for (int i = 0; i < count; ++i) out.row(i) += integral[static_cast<size_t>(i)] * rgb.transpose();
    }
  }
  return out;
}

ShLight environment_light(int order, const Image& img) {
  ShLight light = empty_light(order);
  light.coeffs = integrate_latlong(img, sh_count(order), [order](const Eigen::Vector3d& d, double* y) { sh_eval(order, d.x(), d.y(), d.z(), y); });
  return light;
}

Eigen::MatrixXd sh_rotation(int order, const Eigen::Matrix3d& R) {
  const int K = sh_count(order);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(K, K);
  M(0, 0) = 1;
  const Eigen::Matrix3d Rinv = R.transpose();
  for (int l = 1; l < order; ++l) {
    const int n = 2 * l + 1, samples = 4 * n;
    std::vector<Eigen::Vector3d> dirs = spread_directions(samples);
    Eigen::MatrixXd A(samples, n), B(samples, n);
    Eigen::VectorXd y(K);
    for (int k = 0; k < samples; ++k) {
      sh_eval(order, dirs[static_cast<size_t>(k)].x(), dirs[static_cast<size_t>(k)].y(), dirs[static_cast<size_t>(k)].z(), y.data());
      A.row(k) = y.segment(l * l, n).transpose();
      Eigen::Vector3d d = Rinv * dirs[static_cast<size_t>(k)];
      sh_eval(order, d.x(), d.y(), d.z(), y.data());
      B.row(k) = y.segment(l * l, n).transpose();
    }
    // f(R⁻¹ω) = Σ_m c_m y_m(R⁻¹ω) = Σ_m c_m (B-row) ; we need M with A · (M c) = B · c for all c.
    M.block(l * l, l * l, n, n) = A.colPivHouseholderQr().solve(B);
  }
  return M;
}

ShLight rotate_light(const ShLight& light, const Eigen::Matrix3d& R) {
  ShLight out = light;
  out.coeffs = sh_rotation(light.order, R) * light.coeffs;
  return out;
}

}  // namespace prtsub
