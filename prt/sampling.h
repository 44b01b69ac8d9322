// Deterministic direction sampling for transfer: a cosine-weighted Fibonacci lattice
// per point, decorrelated between points by a seeded random shift.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "prtsub/subdiv/random.h"

namespace prtsub {

//! Right-handed orthonormal frame (t, b, n) for unit n, continuous except at n.z = -1
//! (Duff et al. 2017).
void tangent_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b);

//! Cosine-weighted direction i of `count` in the local frame (z = normal), from a Fibonacci
//! lattice shifted toroidally by (shift_u, shift_v). Every direction is individually
//! cosine-distributed when the shift is uniform, so estimators built on it are unbiased.
Eigen::Vector3d lattice_cosine_direction(uint32_t i, uint32_t count, double shift_u, double shift_v);

}  // namespace prtsub
