#include "cli/progress.h"

#include <unistd.h>

#include <cstdio>

namespace prtsub {

bool stderr_is_terminal() { return ::isatty(2) == 1; }

Progress::Progress(std::string label, size_t total, bool enabled)
    : label_(std::move(label)), total_(total), enabled_(enabled), start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() { finish(); }

void Progress::add(size_t n) {
  size_t done = done_.fetch_add(n) + n;
  if (!enabled_) return;
  int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start_).count();
  int64_t last = last_draw_ns_.load();
  if (now - last < 200'000'000) return;  // five redraws a second at most
  if (!last_draw_ns_.compare_exchange_strong(last, now)) return;
  std::unique_lock<std::mutex> lock(draw_mutex_, std::try_to_lock);
  if (lock.owns_lock()) draw(done);
}

void Progress::draw(size_t done) {
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (total_ == 0) {  // total unknown: a count
    std::fprintf(stderr, "\r%s %zu done, %.1fs elapsed   ", label_.c_str(), done, secs);
    std::fflush(stderr);
    return;
  }
  double frac = double(done) / double(total_);
  double eta = frac > 0 ? secs * (1 - frac) / frac : 0;
  std::fprintf(stderr, "\r%s %5.1f%% (%zu/%zu) %.1fs elapsed, ~%.0fs left   ", label_.c_str(), 100 * frac, done, total_, secs, eta);
  std::fflush(stderr);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (!enabled_) return;
  std::lock_guard<std::mutex> lock(draw_mutex_);
  draw(done_.load());
  std::fputc('\n', stderr);
}

}  // namespace prtsub
