// Writing an output file so that it is either the old file or the whole new one, never half,
// and never replacing what is not a regular file.
#pragma once

#include <string>

namespace prtsub {

//! Writes `bytes` to `path`:
//!  - a regular file, or a new one: into a file beside it, then renamed over it. Where the
//!    filesystem has O_TMPFILE (ext4, xfs, btrfs, tmpfs) that file has no name while it is
//!    written and synced, so nothing is left whatever stops the process (even SIGKILL); it is
//!    named ".NAME.prtsub-tmp.PID.N" only for the rename (elsewhere, from the start). Every
//!    write, sync and close is checked (a full disk is an IoError naming the file), and the
//!    temporary name is removed on every error, and by remove_temporary_files() when a signal
//!    stops the process;
//!  - a character device (/dev/null, a terminal): written in place, every error checked (so a
//!    full device is reported, not hidden);
//!  - anything else that exists (a directory, FIFO, socket or block device): refused, untouched.
//! \throw IoError naming the file and the reason
void write_file_atomically(const std::string& path, const std::string& bytes);

//! Checks before any work that write_file_atomically(path, ...) can succeed: the target is
//! refused as above, or its directory does not take a new file. Leaves nothing behind.
//! \throw IoError naming the file and the reason
void check_output_path(const std::string& path);

//! Removes the temporary files of writes in progress. Async-signal-safe: a program calls it
//! from its SIGINT and SIGTERM handlers (the prtsub tool does) so that a stopped run leaves
//! its old outputs intact and no temporary file behind.
void remove_temporary_files();

}  // namespace prtsub
