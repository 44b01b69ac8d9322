#include "cli_helpers.h"

#include "cli/commands.h"

namespace prtsub::test {

int run_prtsub(std::vector<std::string> args) {
  args.insert(args.begin(), "prtsub");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return run_cli(static_cast<int>(argv.size()), argv.data());
}

}  // namespace prtsub::test
