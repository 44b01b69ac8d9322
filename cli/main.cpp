#include <csignal>

#include "cli/commands.h"
#include "prtsub/prt/output_file.h"

namespace {

// Stopped by a signal: remove the temporary files of writes in progress (so the old outputs stay
// as they were and nothing half-written is left), then die of the signal as the caller expects.
extern "C" void on_stop(int signal) {
  prtsub::remove_temporary_files();
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGINT, on_stop);
  std::signal(SIGTERM, on_stop);
  return prtsub::run_cli(argc, argv);
}
