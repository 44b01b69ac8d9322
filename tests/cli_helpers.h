// What the command-line tests share beyond the procedural fixtures.
#pragma once

#include <string>
#include <vector>

#include "helpers.h"

namespace prtsub::test {

//! Runs a prtsub command line in-process ("prtsub" is prepended); returns its exit status.
int run_prtsub(std::vector<std::string> args);

//! The number a --report JSON gives `key`, or NaN when it has none.
double json_number(const std::string& json, const std::string& key);

}  // namespace prtsub::test
