// The one clock every stage times itself with: seconds since start, and laps.
#pragma once

#include <chrono>

namespace prtsub {

class Stopwatch {
 public:
  //! Seconds since the last lap (or the start), and starts the next lap.
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }
  //! Seconds since the last lap, without starting a new one.
  double split() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count(); }
  //! Seconds since the start.
  double total() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_ = start_;
};

}  // namespace prtsub
