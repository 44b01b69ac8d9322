// A lat-long environment map from a function of direction, for the light and image tests.
#pragma once

#include <functional>

#include "prtsub/prt/lights.h"

namespace prtsub::test {

//! A w×h lat-long map holding f at each texel's centre direction (the mapping of
//! environment_light), three channels.
inline Image latlong(int w, int h, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f) {
  Image img;
  img.width = w, img.height = h, img.channels = 3;
  img.pixels.resize(static_cast<size_t>(w) * h * 3);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const Eigen::Vector3d v = f(latlong_direction((c + 0.5) / w, (r + 0.5) / h));
      for (int k = 0; k < 3; ++k) img.at(c, r, k) = static_cast<float>(v[k]);
    }
  return img;
}

}  // namespace prtsub::test
