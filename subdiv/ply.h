// A generic PLY reader (ASCII, binary little- and big-endian) used for input meshes and
// for reading assets back. Every malformation becomes an InputError naming the file.
#pragma once

#include <cstdint>

#include <string>
#include <vector>

namespace prtsub {

//! One element of a PLY file. Scalar properties become one column of doubles each;
//! list properties a CSR pair (offsets has count+1 entries).
struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<std::string> scalar_names;
  std::vector<std::vector<double>> scalars;  //!< [property][row]
  //! [property]: the stored value that stands for 1.0 in a normalised quantity such as a colour
  //! (255 for uchar, 65535 for ushort, 2³²−1 for uint, the largest positive value for signed
  //! integers); 1 for float and double
  std::vector<double> scalar_unit;
  std::vector<std::string> list_names;
  std::vector<std::vector<size_t>> list_offsets;  //!< [property][row + 1]
  std::vector<std::vector<double>> list_values;   //!< [property][flattened]

  //! Column of a scalar property, or nullptr.
  const std::vector<double>* scalar(const std::string& property) const;
  //! Index of a list property, or -1.
  int list(const std::string& property) const;
};

struct PlyFile {
  std::string format;  //!< ascii, binary_little_endian or binary_big_endian
  std::vector<std::string> comments;
  std::vector<PlyElement> elements;
  const PlyElement* element(const std::string& name) const;
};

//! Reads a whole PLY file.
//! \throw IoError if the file cannot be read, InputError if it is malformed or truncated.
PlyFile read_ply(const std::string& path);

//! Parses PLY bytes; `path` only names the source in messages.
//! An index stored as a number (PLY lists may be float): finite, integral and within ±2⁵³, or an
//! InputError naming `what`. Range checks are the caller's.
int64_t index_value(double v, const std::string& what);

PlyFile parse_ply(const std::string& bytes, const std::string& path);

//! Reads a file into memory. \throw IoError naming the path.
std::string read_file_bytes(const std::string& path);

}  // namespace prtsub
