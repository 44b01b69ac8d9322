#include "cli/args.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace prtsub {

void parse_size(const std::string& text, const std::string& option, int& width, int& height) {
  int a = 0, b = 0;
  char extra = 0;
  if (std::sscanf(text.c_str(), "%d,%d%c", &a, &b, &extra) != 2 || a < 1 || b < 1 || a > 16384 || b > 16384)
    throw UsageError(option + ": expected W,H with each 1 to 16384, got '" + text + "'");
  width = a, height = b;
}

ArgParser::ArgParser(std::string command, std::string summary)
    : command_(std::move(command)), summary_(std::move(summary)) {}

void ArgParser::positional(const std::string& name, const std::string& help, std::string* out) {
  positionals_.emplace_back(name, out);
  positional_help_.push_back(help);
}

void ArgParser::option(const std::string& name, const std::string& metavar, const std::string& help, std::string* out) {
  options_.push_back({name, metavar, help, [name, out](const std::string& v) {
                        if (v.empty()) throw UsageError(name + ": expected a value");
                        *out = v;
                      }});
}

void ArgParser::option(const std::string& name, const std::string& metavar, const std::string& help, int* out, int lo, int hi) {
  options_.push_back({name, metavar, help + " [" + std::to_string(lo) + ".." + std::to_string(hi) + ", default " + std::to_string(*out) + "]",
                      [name, out, lo, hi](const std::string& v) {
                        long long x = 0;
                        auto r = std::from_chars(v.data(), v.data() + v.size(), x);
                        if (r.ec != std::errc() || r.ptr != v.data() + v.size())
                          throw UsageError(name + ": expected an integer, got '" + v + "'");
                        if (x < lo || x > hi)
                          throw UsageError(name + ": must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + v);
                        *out = static_cast<int>(x);
                      }});
}

void ArgParser::option(const std::string& name, const std::string& metavar, const std::string& help, uint64_t* out) {
  options_.push_back({name, metavar, help + " [default " + std::to_string(*out) + "]", [name, out](const std::string& v) {
                        uint64_t x = 0;
                        auto r = std::from_chars(v.data(), v.data() + v.size(), x);
                        if (r.ec != std::errc() || r.ptr != v.data() + v.size())
                          throw UsageError(name + ": expected a non-negative integer, got '" + v + "'");
                        *out = x;
                      }});
}

void ArgParser::option(const std::string& name, const std::string& metavar, const std::string& help, size_t* out, size_t lo, size_t hi) {
  options_.push_back({name, metavar, help + " [" + std::to_string(lo) + ".." + std::to_string(hi) + ", default " + std::to_string(*out) + "]",
                      [name, out, lo, hi](const std::string& v) {
                        unsigned long long x = 0;
                        auto r = std::from_chars(v.data(), v.data() + v.size(), x);
                        if (r.ec != std::errc() || r.ptr != v.data() + v.size())
                          throw UsageError(name + ": expected a non-negative integer, got '" + v + "'");
                        if (x < lo || x > hi)
                          throw UsageError(name + ": must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + v);
                        *out = static_cast<size_t>(x);
                      }});
}

void ArgParser::option(const std::string& name, const std::string& metavar, const std::string& help, double* out, double lo, double hi) {
  std::ostringstream range;
  range << " [" << lo << ".." << hi << ", default " << *out << "]";
  options_.push_back({name, metavar, help + range.str(), [name, out, lo, hi](const std::string& v) {
                        double x = 0;
                        auto r = std::from_chars(v.data(), v.data() + v.size(), x);
                        if (r.ec != std::errc() || r.ptr != v.data() + v.size() || !std::isfinite(x))
                          throw UsageError(name + ": expected a number, got '" + v + "'");
                        if (x < lo || x > hi) {
                          std::ostringstream msg;
                          msg << name << ": must be between " << lo << " and " << hi << ", got " << v;
                          throw UsageError(msg.str());
                        }
                        *out = x;
                      }});
}

void ArgParser::option(const std::string& name, const std::string& metavar, const std::string& help,
                       std::vector<std::string>* out) {
  options_.push_back({name, metavar, help + " (repeatable)", [name, out](const std::string& v) {
                        if (v.empty()) throw UsageError(name + ": expected a value");
                        out->push_back(v);
                      }});
}

void ArgParser::flag(const std::string& name, const std::string& help, bool* out) {
  options_.push_back({name, "", help, [out](const std::string&) { *out = true; }, false});
}

void ArgParser::alias(const std::string& short_name, const std::string& long_name) {
  aliases_.emplace_back(short_name, long_name);
}

const ArgParser::Spec* ArgParser::find(const std::string& name) const {
  std::string n = name;
  for (const auto& [s, l] : aliases_)
    if (s == name) n = l;
  for (const Spec& s : options_)
    if (s.name == n) return &s;
  return nullptr;
}

bool ArgParser::parse(int argc, char** argv, int first) {
  size_t next_positional = 0;
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(help().c_str(), stdout);
      return false;
    }
    if (arg.size() > 1 && arg[0] == '-' && !(std::isdigit(static_cast<unsigned char>(arg[1])) || arg[1] == '.')) {
      std::string value;
      bool inline_value = false;
      size_t eq = arg.find('=');
      if (arg.rfind("--", 0) == 0 && eq != std::string::npos) {
        value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
        inline_value = true;
      }
      const Spec* spec = find(arg);
      if (!spec) throw UsageError(command_ + ": unknown option '" + arg + "' (see prtsub " + command_ + " --help)");
      if (!spec->takes_value) {
        if (inline_value) throw UsageError(spec->name + ": takes no value");
      } else if (!inline_value) {
        if (i + 1 >= argc) throw UsageError(spec->name + ": expected a value");
        value = argv[++i];
      }
      spec->set(value);
      for (const auto& [name, hook] : hooks_)
        if (name == spec->name) hook();
    } else {
      if (next_positional >= positionals_.size()) {
        if (!rest_) throw UsageError(command_ + ": unexpected argument '" + arg + "'");
        rest_->push_back(arg);
        continue;
      }
      *positionals_[next_positional++].second = arg;
    }
  }
  if (next_positional < positionals_.size())
    throw UsageError(command_ + ": missing " + positionals_[next_positional].first + " (see prtsub " + command_ + " --help)");
  return true;
}

std::string ArgParser::help() const {
  std::ostringstream out;
  out << "usage: prtsub " << command_;
  for (const auto& p : positionals_) out << " " << p.first;
  if (rest_) out << " [" << rest_name_ << "...]";
  out << " [options]\n\n" << summary_ << "\n\n";
  for (size_t i = 0; i < positionals_.size(); ++i)
    out << "  " << positionals_[i].first << "\n      " << positional_help_[i] << "\n";
  out << "options:\n";
  for (const Spec& s : options_) {
    std::string names = s.name;
    for (const auto& [sh, l] : aliases_)
      if (l == s.name) names = sh + ", " + names;
    std::string help = s.help;  // continuation lines indented like the first
    for (size_t at = help.find('\n'); at != std::string::npos; at = help.find('\n', at + 7)) help.insert(at + 1, "      ");
    out << "  " << names << " " << s.metavar << "\n      " << help << "\n";
  }
  out << "  -h, --help\n      show this help\n";
  return out.str();
}

}  // namespace prtsub
