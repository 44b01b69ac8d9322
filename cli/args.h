// A small declarative argument parser: each option names its target and range, --help is
// generated, and every error names the option at fault.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

//! A command-line mistake; the CLI exits with status 2.
class UsageError : public InputError {
 public:
  using InputError::InputError;
};

//! Parses "W,H" (each 1 to 16384) for `option`. \throw UsageError naming the option
void parse_size(const std::string& text, const std::string& option, int& width, int& height);

class ArgParser {
 public:
  ArgParser(std::string command, std::string summary);

  void positional(const std::string& name, const std::string& help, std::string* out);
  //! Arguments after the declared positionals are appended here instead of being an error.
  void rest(const std::string& name, std::vector<std::string>* out) { rest_name_ = name, rest_ = out; }
  void option(const std::string& name, const std::string& metavar, const std::string& help, std::string* out);
  void option(const std::string& name, const std::string& metavar, const std::string& help, int* out, int lo, int hi);
  void option(const std::string& name, const std::string& metavar, const std::string& help, uint64_t* out);
  void option(const std::string& name, const std::string& metavar, const std::string& help, size_t* out, size_t lo, size_t hi);
  void option(const std::string& name, const std::string& metavar, const std::string& help, double* out, double lo, double hi);
  //! A repeatable option: every occurrence is appended.
  void option(const std::string& name, const std::string& metavar, const std::string& help, std::vector<std::string>* out);
  //! One of an enum's values by name; the default shown is *out's. A name not in `values` is a
  //! UsageError listing the names.
  template <class E>
  void choice(const std::string& name, const std::string& help, E* out, std::vector<E> values, const char* (*name_of)(E)) {
    std::string metavar, list;
    for (E v : values) metavar += (metavar.empty() ? "" : "|") + std::string(name_of(v)), list += (list.empty() ? "" : ", ") + std::string(name_of(v));
    options_.push_back({name, metavar, help + " [default " + name_of(*out) + "]", [=](const std::string& v) {
                          for (E e : values)
                            if (v == name_of(e)) {
                              *out = e;
                              return;
                            }
                          throw UsageError(name + ": unknown value '" + v + "' (" + list + ")");
                        }});
  }
  //! An option without a value.
  void flag(const std::string& name, const std::string& help, bool* out);
  //! A short alias such as -o for an option already declared.
  void alias(const std::string& short_name, const std::string& long_name);
  //! Calls `f` whenever the option is given (after its value is set): for a default that depends
  //! on whether the user chose a value at all.
  void when_given(const std::string& name, std::function<void()> f) { hooks_.emplace_back(name, std::move(f)); }

  //! Parses argv[first..argc). Returns false when --help was asked for (and printed).
  //! \throw UsageError naming the option for unknown options, missing or bad values
  bool parse(int argc, char** argv, int first);
  std::string help() const;

 private:
  struct Spec {
    std::string name, metavar, help;
    std::function<void(const std::string&)> set;
    bool takes_value = true;
  };
  const Spec* find(const std::string& name) const;
  std::string command_, summary_;
  std::vector<Spec> options_;
  std::vector<std::pair<std::string, std::string>> aliases_;
  std::vector<std::pair<std::string, std::string*>> positionals_;
  std::string rest_name_;
  std::vector<std::string>* rest_ = nullptr;
  std::vector<std::string> positional_help_;
  std::vector<std::pair<std::string, std::function<void()>>> hooks_;
};

}  // namespace prtsub
