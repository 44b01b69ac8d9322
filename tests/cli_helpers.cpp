#include "cli_helpers.h"

#include "cli/commands.h"

namespace prtsub::test {

int run_prtsub(std::vector<std::string> args) {
  args.insert(args.begin(), "prtsub");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return run_cli(static_cast<int>(argv.size()), argv.data());
}

double json_number(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\": ");
  return at == std::string::npos ? std::nan("") : std::atof(json.c_str() + at + key.size() + 4);
}

}  // namespace prtsub::test
