// PLY parsing. The header is read line by line; the body is decoded per element, with every
// binary read checked against the bytes left so that a truncated or lying header is an error,
// never an out-of-bounds read or a huge allocation.
#include "prtsub/subdiv/ply.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

PlyType parse_type(const std::string& s, const std::string& path) {
  if (s == "char" || s == "int8") return PlyType::Int8;
  if (s == "uchar" || s == "uint8") return PlyType::UInt8;
  if (s == "short" || s == "int16") return PlyType::Int16;
  if (s == "ushort" || s == "uint16") return PlyType::UInt16;
  if (s == "int" || s == "int32") return PlyType::Int32;
  if (s == "uint" || s == "uint32") return PlyType::UInt32;
  if (s == "float" || s == "float32") return PlyType::Float32;
  if (s == "double" || s == "float64") return PlyType::Float64;
  throw InputError(path + ": PLY header has unknown property type '" + s + "'");
}

size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8: return 1;
    case PlyType::Int16:
    case PlyType::UInt16: return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 0;
}

struct PropertyDecl {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
  PlyType type = PlyType::Float32;
};

struct ElementDecl {
  std::string name;
  size_t count = 0;
  std::vector<PropertyDecl> properties;
};

// Binary cursor over the body; every read is bounds-checked.
class BinaryReader {
 public:
  BinaryReader(const std::string& bytes, size_t pos, bool big_endian, const std::string& path)
      : bytes_(bytes), pos_(pos), big_(big_endian), path_(path) {}

  double read(PlyType t, const std::string& where) {
    size_t n = type_size(t);
    if (pos_ + n > bytes_.size())
      throw InputError(path_ + ": truncated binary PLY (data ends inside " + where + ")");
    unsigned char buf[8];
    std::memcpy(buf, bytes_.data() + pos_, n);
    pos_ += n;
    if (big_)
      for (size_t i = 0; i < n / 2; ++i) std::swap(buf[i], buf[n - 1 - i]);
    switch (t) {
      case PlyType::Int8: { int8_t v; std::memcpy(&v, buf, 1); return v; }
      case PlyType::UInt8: { uint8_t v; std::memcpy(&v, buf, 1); return v; }
      case PlyType::Int16: { int16_t v; std::memcpy(&v, buf, 2); return v; }
      case PlyType::UInt16: { uint16_t v; std::memcpy(&v, buf, 2); return v; }
      case PlyType::Int32: { int32_t v; std::memcpy(&v, buf, 4); return v; }
      case PlyType::UInt32: { uint32_t v; std::memcpy(&v, buf, 4); return v; }
      case PlyType::Float32: { float v; std::memcpy(&v, buf, 4); return v; }
      case PlyType::Float64: { double v; std::memcpy(&v, buf, 8); return v; }
    }
    return 0;
  }
  size_t remaining() const { return bytes_.size() - pos_; }

 private:
  const std::string& bytes_;
  size_t pos_;
  bool big_;
  const std::string& path_;
};

// Whitespace tokenizer over the ASCII body.
class AsciiReader {
 public:
  AsciiReader(const std::string& bytes, size_t pos, const std::string& path)
      : bytes_(bytes), pos_(pos), path_(path) {}

  double read(const std::string& where) {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    if (pos_ >= bytes_.size())
      throw InputError(path_ + ": truncated ASCII PLY (data ends inside " + where + ")");
    size_t start = pos_;
    while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    double v = 0;
    auto res = std::from_chars(bytes_.data() + start, bytes_.data() + pos_, v);
    if (res.ec != std::errc() || res.ptr != bytes_.data() + pos_)
      throw InputError(path_ + ": bad number '" + bytes_.substr(start, std::min<size_t>(pos_ - start, 32)) +
                       "' in " + where);
    return v;
  }

 private:
  const std::string& bytes_;
  size_t pos_;
  const std::string& path_;
};

// The value of a type that stands for 1.0 in a normalised quantity (a colour).
double type_unit(PlyType t) {
  switch (t) {
    case PlyType::Int8: return 127;
    case PlyType::UInt8: return 255;
    case PlyType::Int16: return 32767;
    case PlyType::UInt16: return 65535;
    case PlyType::Int32: return 2147483647.0;
    case PlyType::UInt32: return 4294967295.0;
    case PlyType::Float32:
    case PlyType::Float64: return 1;
  }
  return 1;
}

// Smallest number of bytes one row of the element can take, to reject lying counts early.
size_t min_row_bytes(const ElementDecl& e) {
  size_t n = 0;
  for (const auto& p : e.properties) n += p.is_list ? type_size(p.count_type) : type_size(p.type);
  return n;
}

}  // namespace

const std::vector<double>* PlyElement::scalar(const std::string& property) const {
  for (size_t i = 0; i < scalar_names.size(); ++i)
    if (scalar_names[i] == property) return &scalars[i];
  return nullptr;
}

int PlyElement::list(const std::string& property) const {
  for (size_t i = 0; i < list_names.size(); ++i)
    if (list_names[i] == property) return static_cast<int>(i);
  return -1;
}

const PlyElement* PlyFile::element(const std::string& name) const {
  for (const auto& e : elements)
    if (e.name == name) return &e;
  return nullptr;
}

std::string read_file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open file (" + std::strerror(errno) + ")");
  // A regular file is read in one call into a string of its size: a stream copy grows its
  // buffer by doubling and copies it out again (a tenth of a second on a 7 MB scan). Anything
  // else (a pipe, a device) goes through the stream.
  std::error_code ec;
  const auto size = std::filesystem::is_regular_file(path, ec) ? std::filesystem::file_size(path, ec) : std::uintmax_t(0);
  if (!ec && size > 0) {
    std::string bytes(static_cast<size_t>(size), '\0');
    in.read(bytes.data(), static_cast<std::streamsize>(size));
    if (static_cast<std::uintmax_t>(in.gcount()) == size) return bytes;
    if (in.bad()) throw IoError(path + ": read error");
    // Shorter than it was a moment ago (being rewritten): what is there, through the stream.
    in.clear();
    in.seekg(0);
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw IoError(path + ": read error");
  return ss.str();
}

int64_t index_value(double v, const std::string& what) {
  if (!std::isfinite(v) || v != std::floor(v) || std::abs(v) > 9007199254740992.0) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    throw InputError(what + " is not an integer index (" + buf + ")");
  }
  return static_cast<int64_t>(v);
}

PlyFile read_ply(const std::string& path) { return parse_ply(read_file_bytes(path), path); }

namespace {

// The header: format, comments and element declarations. Returns the offset of the body.
size_t parse_header(const std::string& bytes, const std::string& path, PlyFile& file, std::vector<ElementDecl>& decls) {
  size_t pos = 0;
  for (int line_no = 1; pos < bytes.size(); ++line_no) {
    size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) break;
    std::string line = bytes.substr(pos, eol - pos);
    pos = eol + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string kw;
    ls >> kw;
    if (kw == "ply" || kw.empty() || kw == "obj_info") continue;
    if (kw == "end_header") {
      if (file.format.empty()) throw InputError(path + ": PLY header has no format line");
      return pos;
    }
    if (kw == "comment") {
      file.comments.push_back(line.size() > 8 ? line.substr(8) : "");
    } else if (kw == "format") {
      std::string version;
      ls >> file.format >> version;
      if (file.format != "ascii" && file.format != "binary_little_endian" && file.format != "binary_big_endian")
        throw InputError(path + ": unknown PLY format '" + file.format + "'");
    } else if (kw == "element") {
      ElementDecl e;
      long long count = -1;
      ls >> e.name >> count;
      if (!ls || count < 0) throw InputError(path + ": bad element line " + std::to_string(line_no) + " in PLY header");
      for (const ElementDecl& d : decls)
        if (d.name == e.name) throw InputError(path + ": PLY header declares element '" + e.name + "' twice (line " + std::to_string(line_no) + ")");
      e.count = static_cast<size_t>(count);
      decls.push_back(e);
    } else if (kw == "property") {
      if (decls.empty())
        throw InputError(path + ": PLY property before any element (header line " + std::to_string(line_no) + ")");
      PropertyDecl p;
      std::string t;
      ls >> t;
      if (t == "list") {
        std::string ct, vt;
        ls >> ct >> vt >> p.name;
        p.is_list = true;
        p.count_type = parse_type(ct, path);
        p.type = parse_type(vt, path);
      } else {
        p.type = parse_type(t, path);
        ls >> p.name;
      }
      if (p.name.empty()) throw InputError(path + ": PLY property without a name");
      decls.back().properties.push_back(p);
    } else {
      throw InputError(path + ": unknown PLY header keyword '" + kw + "' on line " + std::to_string(line_no));
    }
  }
  throw InputError(path + ": PLY header has no end_header");
}

// Columns of one element, laid out as its declaration says: scalars and lists apart.
PlyElement empty_element(const ElementDecl& d, std::vector<int>& slot) {
  PlyElement e;
  e.name = d.name;
  e.count = d.count;
  slot.resize(d.properties.size());
  for (size_t k = 0; k < d.properties.size(); ++k) {
    if (d.properties[k].is_list) {
      slot[k] = static_cast<int>(e.list_names.size());
      e.list_names.push_back(d.properties[k].name);
      e.list_offsets.emplace_back(1, 0);
      e.list_offsets.back().reserve(d.count + 1);
      e.list_values.emplace_back();
    } else {
      slot[k] = static_cast<int>(e.scalar_names.size());
      e.scalar_names.push_back(d.properties[k].name);
      e.scalar_unit.push_back(type_unit(d.properties[k].type));
      e.scalars.emplace_back();
      e.scalars.back().reserve(d.count);
    }
  }
  return e;
}

}  // namespace

PlyFile parse_ply(const std::string& bytes, const std::string& path) {
  if (bytes.compare(0, 3, "ply") != 0) throw InputError(path + ": not a PLY file (no 'ply' magic)");
  PlyFile file;
  std::vector<ElementDecl> decls;
  const size_t pos = parse_header(bytes, path, file, decls);
  const bool ascii = file.format == "ascii";
  BinaryReader bin(bytes, pos, file.format == "binary_big_endian", path);
  AsciiReader asc(bytes, pos, path);
  auto read = [&](PlyType t, const std::string& where) { return ascii ? asc.read(where) : bin.read(t, where); };
  for (const ElementDecl& d : decls) {
    if (!ascii && d.count > 0 && min_row_bytes(d) > 0 && d.count > bin.remaining() / min_row_bytes(d))
      throw InputError(path + ": truncated binary PLY (header declares " + std::to_string(d.count) + " " + d.name +
                       " rows, the file is too short for them)");
    if (ascii && d.count > bytes.size())  // each row takes at least one byte
      throw InputError(path + ": truncated ASCII PLY (header declares " + std::to_string(d.count) + " " + d.name + " rows)");
    // Rows without properties hold no bytes, so nothing bounds how many a header may claim: a
    // reader would count to 10^18, and a consumer would size its arrays by the claim (the fuzzer
    // found 2.7·10^10 vertex rows in a 200-byte asset). No writer makes such an element.
    if (d.properties.empty() && d.count > 0)
      throw InputError(path + ": PLY element '" + d.name + "' declares " + std::to_string(d.count) + " rows but no properties");
    std::vector<int> slot;
    PlyElement e = empty_element(d, slot);
    const std::string where = "element '" + d.name + "'";
    for (size_t row = 0; row < d.count; ++row) {
      for (size_t k = 0; k < d.properties.size(); ++k) {
        const PropertyDecl& p = d.properties[k];
        if (!p.is_list) {
          e.scalars[slot[k]].push_back(read(p.type, where));
          continue;
        }
        const double n = read(p.count_type, where);
        if (!(n >= 0) || n > 1e6 || n != std::floor(n))
          throw InputError(path + ": bad list length " + std::to_string(n) + " in " + where + " row " + std::to_string(row));
        auto& values = e.list_values[slot[k]];
        for (size_t i = 0; i < static_cast<size_t>(n); ++i) values.push_back(read(p.type, where));
        e.list_offsets[slot[k]].push_back(values.size());
      }
    }
    file.elements.push_back(std::move(e));
  }
  return file;
}

}  // namespace prtsub
