// A one-line progress display on stderr, shown only on a terminal. Thread-safe: workers
// call add(), and whichever thread finds the display stale redraws it.
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace prtsub {

class Progress {
 public:
  Progress(std::string label, size_t total, bool enabled);
  ~Progress();
  void add(size_t n);
  void finish();

 private:
  void draw(size_t done);
  std::string label_;
  size_t total_;
  bool enabled_;
  bool finished_ = false;
  std::atomic<size_t> done_{0};
  std::atomic<int64_t> last_draw_ns_{0};
  std::mutex draw_mutex_;
  std::chrono::steady_clock::time_point start_;
};

//! True when stderr is a terminal and progress should be drawn.
bool stderr_is_terminal();

}  // namespace prtsub
