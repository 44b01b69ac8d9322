// Outputs never clobber what they should not, a failed write is an error, and a stopped run
// leaves its old outputs intact with no temporary file behind. Devices are made by the test in
// its own directory (mknod, as root; skipped otherwise), never the machine's /dev.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <functional>

#include "cli_helpers.h"
#include "prtsub/prt/asset.h"
#include "prtsub/prt/output_file.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

size_t temporary_files(const std::string& dir) {
  size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    n += e.path().filename().string().find(".prtsub-tmp.") != std::string::npos;
  return n;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const IoError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Output, AFullDeviceIsReportedAndNeverReplaced) {
  test::TempDir dir;
  const std::string full = dir.path("full"), null = dir.path("null");
  if (::mknod(full.c_str(), S_IFCHR | 0666, makedev(1, 7)) != 0 ||
      ::mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0)
    GTEST_SKIP() << "mknod needs root (it has it in CI)";
  // A full device: the write fails and says so; the node stays a node.
  EXPECT_NE(error_of([&] {
              write_file_atomically(full, std::string(100000, 'x'));
            }).find(full + ": write failed (No space left on device)"),
            std::string::npos);
  struct stat st {};
  ASSERT_EQ(::stat(full.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  // /dev/null works as a user expects.
  EXPECT_NO_THROW(write_file_atomically(null, "anything"));
  ASSERT_EQ(::stat(null.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  // Through the tool: exit 1, one line naming the file, the device intact, nothing left beside it.
  const std::string mesh = dir.path("m.obj");
  test::write_obj(mesh, test::cube());
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(test::run_prtsub({"bake", mesh, "-o", full, "--rays", "4"}), 1);
  EXPECT_EQ(
      test::run_prtsub({"bake", mesh, "-o", dir.path("a.ply"), "--rays", "4", "--report", full}),
      1);
  EXPECT_EQ(test::run_prtsub({"bake", mesh, "-o", null, "--rays", "4", "--report", null}), 0);
  testing::internal::GetCapturedStdout();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(err, "prtsub: error: " + full +
                     ": write failed (No space left on device)\n"
                     "prtsub: error: " +
                     full + ": write failed (No space left on device)\n");
  ASSERT_EQ(::stat(full.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_EQ(temporary_files(dir.path("")), 0u);
}

TEST(Output, FifosSocketsAndDirectoriesAreRefusedUntouched) {
  test::TempDir dir;
  const std::string fifo = dir.path("fifo"), sub = dir.path("sub");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0666), 0);
  std::filesystem::create_directory(sub);
  EXPECT_EQ(error_of([&] { write_file_atomically(fifo, "x"); }),
            fifo + ": refusing to write output over a FIFO");
  EXPECT_EQ(error_of([&] { check_output_path(fifo); }),
            fifo + ": refusing to write output over a FIFO");
  EXPECT_EQ(error_of([&] { write_file_atomically(sub, "x"); }),
            sub + ": refusing to write output over a directory");
  struct stat st {};
  ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_TRUE(std::filesystem::is_directory(sub));
  EXPECT_EQ(temporary_files(dir.path("")), 0u);
  // A missing directory is caught before any work.
  EXPECT_NE(error_of([&] {
              check_output_path(dir.path("no/such/a.ply"));
            }).find("cannot create output file in"),
            std::string::npos);
}

TEST(Output, AWriteThatFailsHalfWayLeavesTheOldFileAndNoTemporary) {
  // A file-size limit makes write(2) fail with EFBIG part of the way, as a full disk would.
  test::TempDir dir;
  const std::string path = dir.path("a.txt");
  write_file_atomically(path, "OLD");
  rlimit old{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  auto previous = std::signal(SIGXFSZ, SIG_IGN);
  rlimit small = old;
  small.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::string err = error_of([&] { write_file_atomically(path, std::string(100000, 'x')); });
  ::setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, previous);
  EXPECT_EQ(err, path + ": write failed (File too large)");
  EXPECT_EQ(read_file_bytes(path), "OLD");
  EXPECT_EQ(temporary_files(dir.path("")), 0u);
}

// The temporary files in `dir`, each a complete asset of `triangles` or a failure; then removed.
size_t remove_whole_temporary_assets(const std::string& dir, size_t triangles) {
  size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().filename().string().find(".prtsub-tmp.") == std::string::npos) continue;
    EXPECT_EQ(read_asset(e.path().string()).triangles.size(), triangles)
        << e.path() << " is left part-written";
    std::filesystem::remove(e.path());
    ++n;
  }
  return n;
}

// The tool itself, stopped by `signal` at moments spread over its run (which ends with the write
// of a 4 MB asset: 10,242 vertices of 100 float coefficients): each time, out.ply is the old file
// or a complete asset, and no temporary file is left. With `named_instant`, the one exception is
// a kill that no handler sees landing between the two system calls that name the written, synced
// file and rename it: Linux cannot rename an unnamed file over an existing one. What that leaves
// is a whole asset; it is counted and removed, so each kill is judged by what it left.
void stop_bakes_at_moments_spread_over_the_run(const std::string& signal,
                                               bool named_instant = false) {
  test::TempDir dir;
  const std::string mesh = dir.path("big.obj"), out = dir.path("out.ply");
  test::write_obj(mesh, test::icosphere(5));
  const std::string bake = std::string(PRTSUB_BINARY) + " bake " + mesh + " -o " + out +
                           " --order 10 --rays 1 --fit point > /dev/null 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(std::system(bake.c_str()), 0);
  const double whole = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const size_t triangles = read_asset(out).triangles.size();
  int stopped = 0, finished = 0;
  size_t named = 0;
  for (int i = 0; i < 8; ++i) {
    test::write_text(out, "OLD");
    const double at = whole * (0.3 + 0.7 * i / 7.0);
    const int status =
        std::system(("timeout -s " + signal + " " + std::to_string(at) + " " + bake).c_str());
    const std::string bytes = read_file_bytes(out);
    if (bytes == "OLD")
      ++stopped;
    else
      EXPECT_EQ(read_asset(out).triangles.size(), triangles)
          << "stopped at " << at << " s (status " << status << ")";
    finished += bytes != "OLD";
    if (named_instant)
      named += remove_whole_temporary_assets(dir.path(""), triangles);
    else
      EXPECT_EQ(temporary_files(dir.path("")), 0u)
          << "stopped by SIG" << signal << " at " << at << " s";
  }
  std::printf("SIG%s: whole run %.2f s; %d runs stopped with the old file in place, %d finished",
              signal.c_str(), whole, stopped, finished);
  if (named_instant) std::printf("; %zu left a whole asset under its temporary name", named);
  std::printf("\n");
}

TEST(Output, ABakeStoppedAtAnyMomentLeavesTheOldOutputOrTheWholeNewOne) {
  stop_bakes_at_moments_spread_over_the_run("TERM");
}

TEST(Output, ABakeKilledOutrightLeavesNoPartWrittenFileWhereTheFilesystemHasUnnamedFiles) {
  // SIGKILL runs no handler: only a file with no name while it is written leaves nothing behind.
  test::TempDir dir;
#ifdef O_TMPFILE
  const int fd = ::open(dir.path("").c_str(), O_TMPFILE | O_WRONLY, 0600);
#else
  const int fd = -1;
#endif
  if (fd < 0)
    GTEST_SKIP()
        << dir.path("")
        << ": this filesystem has no O_TMPFILE, so a killed write leaves its temporary file";
  ::close(fd);
  stop_bakes_at_moments_spread_over_the_run("KILL", true);
}

}  // namespace
}  // namespace prtsub
