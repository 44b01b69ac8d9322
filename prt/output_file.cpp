// Atomic outputs. The bytes go into a file beside the target (same directory, so the rename is
// atomic) through write(2), are synced and closed, every step checked, and the file is then
// renamed over the target.
//
// Where the filesystem allows (Linux's O_TMPFILE: ext4, xfs, btrfs, tmpfs), that file has no name
// while it is written and synced: whatever stops the process then (a signal, SIGKILL, the OOM
// killer, a crash) the kernel reclaims it and nothing is left. It is linked to a temporary name
// only for the instant before the rename. Elsewhere it is a named temporary file from the start.
// While a temporary name exists it sits in a fixed table of slots, which remove_temporary_files()
// walks with only async-signal-safe calls (unlink), so that a signal handler can clean up: the
// table is written before the name is created and cleared after the rename.
//
// Character devices are written in place (there is nothing to rename over: /dev/null must keep
// working, and /dev/full must say it is full); every other non-regular target is refused, because
// renaming over it would replace it (as root, a device node) with a file.
#include "prtsub/prt/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

constexpr int kSlots = 64;
constexpr size_t kPathMax = 4096;
// A slot is free, claimed (its path being copied: the handler must not read it), or ready.
enum SlotState : int { kFree = 0, kClaimed = 1, kReady = 2 };
struct Slot {
  std::atomic<int> state{kFree};
  char path[kPathMax];
};
Slot g_slots[kSlots];
std::atomic<unsigned> g_counter{0};

int claim_slot(const std::string& tmp) {
  if (tmp.size() >= kPathMax) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kClaimed)) continue;
    std::memcpy(g_slots[i].path, tmp.c_str(), tmp.size() + 1);
    g_slots[i].state.store(kReady);
    return i;
  }
  return -1;  // more than kSlots writes at once: this one is not cleaned up by a signal
}

void release_slot(int slot) {
  if (slot >= 0) g_slots[slot].state.store(kFree);
}

std::string errno_text() {
  return std::strerror(errno);
}

// Every byte through write(2), retried on EINTR and short writes.
bool write_all(int fd, const std::string& bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

std::string directory_of(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
}

std::string temporary_name(const std::string& path) {
  const size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  return dir + "." + name + ".prtsub-tmp." + std::to_string(::getpid()) + "." +
         std::to_string(g_counter++);
}

// What kind of target this is: 0 none yet, 1 regular file, 2 character device; IoError otherwise.
int target_kind(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return 0;
    throw IoError(path + ": cannot examine output path (" + errno_text() + ")");
  }
  if (S_ISREG(st.st_mode)) return 1;
  if (S_ISCHR(st.st_mode)) return 2;
  const char* what = S_ISDIR(st.st_mode)    ? "a directory"
                     : S_ISFIFO(st.st_mode) ? "a FIFO"
                     : S_ISSOCK(st.st_mode) ? "a socket"
                     : S_ISBLK(st.st_mode)  ? "a block device"
                                            : "not a regular file";
  throw IoError(path + ": refusing to write output over " + std::string(what));
}

void write_in_place(const std::string& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) throw IoError(path + ": cannot open output device (" + errno_text() + ")");
  const bool written = write_all(fd, bytes);
  const std::string reason = written ? "" : errno_text();
  if (::close(fd) != 0 && written)
    throw IoError(path + ": write failed on close (" + errno_text() + ")");
  if (!written) throw IoError(path + ": write failed (" + reason + ")");
}

// An unnamed file in the target's directory (O_TMPFILE), or -1 where the filesystem or kernel has
// none: the caller then creates a named temporary file instead.
int open_unnamed(const std::string& path) {
#ifdef O_TMPFILE
  const int fd = ::open(directory_of(path).c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
  if (fd >= 0) return fd;
#else
  (void)path;
#endif
  return -1;
}

// Gives the unnamed file `fd` the name `tmp`: by its descriptor where the process may (root), else
// through /proc/self/fd. False if neither works (no /proc, say): the caller falls back.
bool link_unnamed(int fd, const std::string& tmp) {
#ifdef AT_EMPTY_PATH
  if (::linkat(fd, "", AT_FDCWD, tmp.c_str(), AT_EMPTY_PATH) == 0) return true;
#endif
  const std::string proc = "/proc/self/fd/" + std::to_string(fd);
  return ::linkat(AT_FDCWD, proc.c_str(), AT_FDCWD, tmp.c_str(), AT_SYMLINK_FOLLOW) == 0;
}

// Writes and syncs fd. On failure: closes it and sets `what` and `reason`.
bool write_and_sync(int fd, const std::string& bytes, std::string& what, std::string& reason) {
  if (!write_all(fd, bytes))
    what = "write failed";
  else if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS)
    what = "write failed on sync";
  else
    return true;
  reason = errno_text();
  ::close(fd);
  return false;
}

}  // namespace

void remove_temporary_files() {
  for (Slot& slot : g_slots)
    if (slot.state.load() == kReady) ::unlink(slot.path);
}

void write_file_atomically(const std::string& path, const std::string& bytes) {
  if (target_kind(path) == 2) return write_in_place(path, bytes);
  const std::string tmp = temporary_name(path);
  std::string what, reason;
  auto fail = [&](int slot, const std::string& step) {
    if (reason.empty()) reason = errno_text();
    ::unlink(tmp.c_str());
    release_slot(slot);
    throw IoError(path + ": " + (what.empty() ? step : what) + " (" + reason + ")");
  };
  int fd = open_unnamed(path);
  int slot = -1;
  if (fd >= 0) {
    // Written and synced with no name: nothing can be left behind until the link below.
    if (!write_and_sync(fd, bytes, what, reason))
      throw IoError(path + ": " + what + " (" + reason + ")");
    slot = claim_slot(tmp);
    if (!link_unnamed(fd, tmp)) {  // no way to name it: write a named file instead
      ::close(fd);
      release_slot(slot);
      fd = -1;
    }
  }
  const bool unnamed = fd >= 0;
  if (fd < 0) {
    slot = claim_slot(tmp);
    fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) {
      reason = errno_text();
      release_slot(slot);
      throw IoError(path + ": cannot create output file (" + reason + ")");
    }
    if (!write_and_sync(fd, bytes, what, reason)) fail(slot, what);
  }
  if (!unnamed && ::close(fd) != 0) fail(slot, "write failed on close");
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    if (unnamed) ::close(fd);
    fail(slot, "cannot move output into place");
  }
  // An unnamed file was synced before it had a name, so its close can lose nothing; it comes
  // after the rename so that the temporary name lives for two system calls only.
  if (unnamed) ::close(fd);
  release_slot(slot);
}

namespace {

// A named file beside `path` is created and removed, or IoError says why it cannot be.
void probe_named(const std::string& path) {
  const std::string probe = temporary_name(path);
  const int slot = claim_slot(probe);  // a signal between the open and the unlink removes it too
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) {
    const std::string reason = errno_text();
    release_slot(slot);
    throw IoError(path + ": cannot create output file in " + directory_of(path) + " (" + reason +
                  ")");
  }
  ::close(fd);
  ::unlink(probe.c_str());
  release_slot(slot);
}

}  // namespace

void check_output_path(const std::string& path) {
  const int kind = target_kind(path);
  if (kind == 2) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw IoError(path + ": cannot open output device (" + errno_text() + ")");
    ::close(fd);
    return;
  }
  // A new file must be creatable beside the target, where the temporary one will go. An unnamed
  // one shows it and, unlike a named probe, leaves nothing if the process is killed meanwhile.
  const int unnamed = open_unnamed(path);
  if (unnamed >= 0)
    ::close(unnamed);
  else
    probe_named(path);
  if (kind == 1 && ::access(path.c_str(), F_OK) != 0)
    throw IoError(path + ": output file vanished");
}

}  // namespace prtsub
