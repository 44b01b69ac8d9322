// Real spherical harmonics by the stable three-term recurrence in l for fixed m.
//
// With z = cos θ and (x + iy)^m = sin^m θ · e^{imφ}, write P_l^m(z) = sin^m θ · Q_l^m(z)
// (associated Legendre without the Condon-Shortley phase). Q obeys
//   Q_m^m = (2m-1)!!,  Q_{m+1}^m = (2m+1) z Q_m^m,
//   Q_l^m = ((2l-1) z Q_{l-1}^m - (l+m-1) Q_{l-2}^m) / (l-m),
// and y_lm = √2 K_l^m Q_l^m Re/Im((x+iy)^m) for m > 0 / m < 0, K_l^0 Q_l^0 for m = 0, with
// K_l^m = sqrt((2l+1)/(4π) · (l-m)!/(l+m)!). No trigonometry is evaluated, and every factor
// is tabulated once; forward recursion in l is the stable direction for l <= 9.
#include "prtsub/prt/sh.h"

#include <array>
#include <cassert>
#include <cmath>

namespace prtsub {

int transfer_channels(Eigen::Index cols) {
  auto square = [](Eigen::Index k) {
    const auto n = static_cast<Eigen::Index>(std::lround(std::sqrt(static_cast<double>(k))));
    return k > 0 && n * n == k && n <= kMaxShOrder;
  };
  if (square(cols)) return 1;
  if (cols % 3 == 0 && square(cols / 3)) return 3;
  return 0;
}
namespace {

struct Tables {
  // norm[l][m] includes √2 for m > 0 and (2m-1)!! folded into the diagonal start.
  std::array<std::array<double, kMaxShOrder>, kMaxShOrder> norm{};
  std::array<std::array<double, kMaxShOrder>, kMaxShOrder> a{}, b{};  // recurrence
  std::array<double, kMaxShOrder> diag{};                               // (2m-1)!!
  std::array<double, kMaxShOrder> band{};                               // Â_l
  Tables() {
    for (int l = 0; l < kMaxShOrder; ++l)
      for (int m = 0; m <= l; ++m) {
        // (l-m)!/(l+m)! as a product to stay exact-ish.
        double ratio = 1.0;
        for (int k = l - m + 1; k <= l + m; ++k) ratio /= k;
        double k_lm = std::sqrt((2 * l + 1) / (4 * M_PI) * ratio);
        norm[l][m] = m == 0 ? k_lm : std::sqrt(2.0) * k_lm;
        if (l > m + 1) {
          a[l][m] = double(2 * l - 1) / double(l - m);
          b[l][m] = double(l + m - 1) / double(l - m);
        }
      }
    diag[0] = 1.0;
    for (int m = 1; m < kMaxShOrder; ++m) diag[m] = diag[m - 1] * (2 * m - 1);
    for (int l = 0; l < kMaxShOrder; ++l) {
      // Â_l = 2π ∫_0^1 P_l(t) t dt in closed form.
      if (l == 1) {
        band[l] = 2 * M_PI / 3;
      } else if (l % 2 == 1) {
        band[l] = 0;
      } else {
        double fact_l = 1, fact_half = 1;
        for (int k = 2; k <= l; ++k) fact_l *= k;
        for (int k = 2; k <= l / 2; ++k) fact_half *= k;
        double sign = ((l / 2 - 1) % 2 == 0) ? 1.0 : -1.0;
        band[l] = 2 * M_PI * sign / double((l + 2) * (l - 1)) * fact_l /
                  (std::pow(2.0, l) * fact_half * fact_half);
      }
    }
  }
};

const Tables& tables() {
  static const Tables t;
  return t;
}

}  // namespace

void sh_eval(int order, double x, double y, double z, double* out) {
  assert(order >= 1 && order <= kMaxShOrder);
  const Tables& T = tables();
  double c = 1.0, s = 0.0;  // Re, Im of (x + iy)^m
  for (int m = 0; m < order; ++m) {
    double q_prev = 0, q = T.diag[m];  // Q_m^m
    for (int l = m; l < order; ++l) {
      if (l == m + 1) {
        q_prev = q;
        q = (2 * m + 1) * z * q;
      } else if (l > m + 1) {
        double q_next = T.a[l][m] * z * q - T.b[l][m] * q_prev;
        q_prev = q;
        q = q_next;
      }
      double v = T.norm[l][m] * q;
      if (m == 0) {
        out[sh_index(l, 0)] = v;
      } else {
        out[sh_index(l, m)] = v * c;
        out[sh_index(l, -m)] = v * s;
      }
    }
    double c_next = x * c - y * s;
    s = x * s + y * c;
    c = c_next;
  }
}

Eigen::VectorXd sh_eval(int order, const Eigen::Vector3d& d) {
  Eigen::VectorXd out(sh_count(order));
  sh_eval(order, d.x(), d.y(), d.z(), out.data());
  return out;
}

double clamped_cosine_band(int l) { return tables().band[l]; }

void unshadowed_transfer(int order, const Eigen::Vector3d& n, double* out) {
  sh_eval(order, n.x(), n.y(), n.z(), out);
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) out[sh_index(l, m)] *= tables().band[l];
}

Eigen::VectorXd unshadowed_transfer(int order, const Eigen::Vector3d& n) {
  Eigen::VectorXd out(sh_count(order));
  unshadowed_transfer(order, n, out.data());
  return out;
}

}  // namespace prtsub
