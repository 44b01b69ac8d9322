#include "cli/report.h"

#include "cli/escape.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "prtsub/prt/asset.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
void Report::put(Entry e) {
  for (Entry& old : entries_)
    if (old.key == e.key) {
      old = std::move(e);
      return;
    }
  entries_.push_back(std::move(e));
}

const Report::Entry* Report::find(const std::string& key) const {
  for (const Entry& e : entries_)
    if (e.key == key) return &e;
  return nullptr;
}

void Report::set(const std::string& key, double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  put({key, std::isfinite(v) ? buf : "null", v, true, false, ""});
}
void Report::set(const std::string& key, int64_t v) { put({key, std::to_string(v), static_cast<double>(v), true, true, ""}); }
void Report::set(const std::string& key, uint64_t v) { put({key, std::to_string(v), static_cast<double>(v), true, true, ""}); }
void Report::set(const std::string& key, const std::string& v) { put({key, json_quote(v), 0, false, false, v}); }
void Report::set(const std::string& key, bool v) { put({key, v ? "true" : "false", 0, false, false, v ? "yes" : "no"}); }

bool Report::has(const std::string& key) const { return find(key) != nullptr; }

double Report::number(const std::string& key) const {
  const Entry* e = find(key);
  return e && e->is_number ? e->number : 0.0;
}

std::string Report::json() const {
  std::string out = "{\n";
  for (size_t i = 0; i < entries_.size(); ++i)
    out += "  " + json_quote(entries_[i].key) + ": " + entries_[i].json + (i + 1 < entries_.size() ? ",\n" : "\n");
  return out + "}\n";
}

void Report::write(const std::string& path) const { write_file_atomically(path, json()); }

std::string Report::format(const std::string& text) const {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '{') {
      out += text[i];
      continue;
    }
    const size_t close = text.find('}', i);
    if (close == std::string::npos) return out + text.substr(i);
    const std::string field = text.substr(i + 1, close - i - 1);
    const size_t colon = field.find(':');
    const Entry* e = find(field.substr(0, colon));
    if (!e) return "";
    const std::string spec = colon == std::string::npos ? "" : field.substr(colon + 1);
    char buf[64];
    if (!e->is_number) out += e->text;
    else if (!spec.empty() && spec[0] == '%') std::snprintf(buf, sizeof buf, "%.*f%%", std::atoi(spec.c_str() + 1), 100 * e->number), out += buf;
    else if (!spec.empty()) std::snprintf(buf, sizeof buf, "%.*f", std::atoi(spec.c_str()), e->number), out += buf;
    else if (e->is_integer) out += e->json;
    else std::snprintf(buf, sizeof buf, "%.4g", e->number), out += buf;
    i = close;
  }
  return out;
}

void Report::print(FILE* out, std::initializer_list<const char*> lines) const {
  for (const char* line : lines) {
    const std::string text = format(line);
    if (!text.empty()) std::fprintf(out, "%s\n", text.c_str());
  }
}

void check_writable(const std::string& path) { check_output_path(path); }

double peak_memory_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

}  // namespace prtsub
