// A flat JSON report: keys in insertion order, numbers, strings and booleans.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace prtsub {

class Report {
 public:
  void set(const std::string& key, double value);
  void set(const std::string& key, int64_t value);
  void set(const std::string& key, uint64_t value);
  void set(const std::string& key, int value) { set(key, static_cast<int64_t>(value)); }
  void set(const std::string& key, const std::string& value);
  void set(const std::string& key, const char* value) { set(key, std::string(value)); }
  void set(const std::string& key, bool value);
  std::string json() const;
  //! Writes the JSON atomically. \throw IoError
  void write(const std::string& path) const;

 private:
  void put(const std::string& key, std::string encoded);
  std::vector<std::pair<std::string, std::string>> entries_;
};

//! Fails before any work when `path` cannot be created, so a long run never ends in an
//! unwritable path. Leaves nothing behind. \throw IoError
void check_writable(const std::string& path);

//! Peak resident memory of this process so far, in MiB.
double peak_memory_mib();

}  // namespace prtsub
