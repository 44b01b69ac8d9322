#include "prtsub/prt/sampling.h"

#include <cmath>

namespace prtsub {

void tangent_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

Eigen::Vector3d lattice_cosine_direction(uint32_t i, uint32_t count, double shift_u, double shift_v) {
  constexpr double kInvGolden = 0.6180339887498948482;
  double u = (i + 0.5) / count + shift_u;
  u -= std::floor(u);
  double v = i * kInvGolden + shift_v;
  v -= std::floor(v);
  // Malley's method: uniform on the disk, lifted to the hemisphere.
  const double r = std::sqrt(u), phi = 2.0 * M_PI * v;
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - u)));
}

}  // namespace prtsub
