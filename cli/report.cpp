#include "cli/report.h"

#include <sys/resource.h>

#include <cmath>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "subdiv/exceptions.h"

#include "prt/asset.h"

namespace prtsub {
namespace {

std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

}  // namespace

void Report::put(const std::string& key, std::string encoded) {
  for (auto& e : entries_)
    if (e.first == key) {
      e.second = std::move(encoded);
      return;
    }
  entries_.emplace_back(key, std::move(encoded));
}

void Report::set(const std::string& key, double v) {
  if (!std::isfinite(v)) return put(key, "null");
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  put(key, buf);
}
void Report::set(const std::string& key, int64_t v) { put(key, std::to_string(v)); }
void Report::set(const std::string& key, uint64_t v) { put(key, std::to_string(v)); }
void Report::set(const std::string& key, const std::string& v) { put(key, quote(v)); }
void Report::set(const std::string& key, bool v) { put(key, v ? "true" : "false"); }

std::string Report::json() const {
  std::string out = "{\n";
  for (size_t i = 0; i < entries_.size(); ++i)
    out += "  " + quote(entries_[i].first) + ": " + entries_[i].second + (i + 1 < entries_.size() ? ",\n" : "\n");
  return out + "}\n";
}

void Report::write(const std::string& path) const { write_file_atomically(path, json()); }

void check_writable(const std::string& path) {
  const std::string probe = path + ".tmp.probe." + std::to_string(::getpid());
  FILE* f = std::fopen(probe.c_str(), "wb");
  if (!f) throw IoError(path + ": cannot create output file (" + std::strerror(errno) + ")");
  std::fclose(f);
  std::remove(probe.c_str());
}

double peak_memory_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

}  // namespace prtsub
