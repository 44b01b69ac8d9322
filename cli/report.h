// A command's figures, recorded once: a flat list of keys in insertion order (numbers, strings
// and booleans). The JSON report is the record as it is; the printed summary is the same record
// through line templates, so the two can never disagree.
#pragma once

#include <cstdint>
#include <cstdio>
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

  bool has(const std::string& key) const;
  double number(const std::string& key) const;  //!< 0 when absent or not a number
  std::string json() const;
  //! Writes the JSON atomically. \throw IoError
  void write(const std::string& path) const;

  //! `text` with each {key} replaced by the key's value: strings as they are, integers in full,
  //! other numbers with 4 significant digits, {key:N} with N decimals, {key:%N} as a percentage
  //! of a fraction with N decimals. Returns "" if a key is absent, so optional lines vanish.
  std::string format(const std::string& text) const;
  //! Prints format(line) and a newline for each line whose keys are all present.
  void print(FILE* out, std::initializer_list<const char*> lines) const;

 private:
  struct Entry {
    std::string key, json;
    double number = 0;
    bool is_number = false, is_integer = false;
    std::string text;  //!< strings and booleans as printed
  };
  void put(Entry e);
  const Entry* find(const std::string& key) const;
  std::vector<Entry> entries_;
};

//! Fails before any work when `path` cannot be created, so a long run never ends in an
//! unwritable path. Leaves nothing behind. \throw IoError
void check_writable(const std::string& path);

//! Peak resident memory of this process so far, in MiB.
double peak_memory_mib();

}  // namespace prtsub
