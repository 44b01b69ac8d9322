// What first-touch page faults cost on this machine: 200 MB written into fresh memory, three
// times, freeing in between (glibc returns large blocks to the kernel), then three times into
// one reused block. usage: g++ -O2 bench/page_faults.cpp -o pf && ./pf
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

int main() {
  const size_t bytes = size_t(200) << 20;
  auto touch = [&](char* p) {
    const auto t = std::chrono::steady_clock::now();
    std::memset(p, 1, bytes);
    asm volatile("" : : "r"(p) : "memory");  // the writes must happen
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    volatile char keep = p[bytes / 2];
    (void)keep;
    return s;
  };
  for (int r = 0; r < 3; ++r) {
    char* p = static_cast<char*>(std::malloc(bytes));
    std::printf("fresh 200 MB:  %.3f s\n", touch(p));
    std::free(p);
  }
  char* p = static_cast<char*>(std::malloc(bytes));
  touch(p);
  for (int r = 0; r < 3; ++r) std::printf("reused 200 MB: %.3f s\n", touch(p));
  std::free(p);
}
