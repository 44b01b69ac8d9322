// Reading meshes: OBJ, PLY (ASCII and binary), OFF and STL, into a welded Mesh with
// normals from the file or computed with a crease angle, and UVs when the file has them
// (OBJ vt; PLY u v, s t or texture_u texture_v).
#pragma once

#include <string>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

//! What a file says, before validation and welding.
struct RawMesh {
  RowMatrixX3d positions;            //!< #Pin by 3, as in the file
  std::vector<size_t> face_offsets;  //!< #Fin + 1, CSR over face_indices
  std::vector<int64_t> face_indices;  //!< 0-based, possibly out of range (checked later)
  RowMatrixX3d normals;              //!< #N by 3 file normals (may be empty)
  //! Per corner (parallel to face_indices): row of `normals`, or -1. Empty when the file
  //! has per-vertex normals (then normals has one row per position) or none at all.
  std::vector<int64_t> corner_normals;
  RowMatrixX2d texcoords;  //!< #T by 2 file texture coordinates (may be empty)
  //! Per corner: row of `texcoords`, or -1; empty when they are per vertex (one row per position).
  std::vector<int64_t> corner_texcoords;
  //! #Pin by 3 vertex colours as the file stores them, normalised to [0, 1] but still
  //! sRGB-encoded (may be empty)
  RowMatrixX3d colors;
  bool colors_linear = false;  //!< the colours are linear already (built in memory, not read)
  size_t vertices_without_colour = 0;  //!< OBJ: `v` lines without one in a file that has some
};

struct LoadOptions {
  double crease_angle_deg = kDefaultCreaseAngleDeg;  //!< computed normals: edges sharper than this are creases
};

//! Reads a mesh file; the format is chosen by the file's extension (case-insensitive).
//! \throw IoError if unreadable, InputError naming the file and the problem otherwise.
Mesh load_mesh(const std::string& path, const LoadOptions& options = {});

//! load_mesh on bytes already read: the format is chosen by `path`'s extension.
Mesh parse_mesh(const std::string& bytes, const std::string& path, const LoadOptions& options = {});

//! Parses one format from bytes (path only names the source in messages).
RawMesh parse_obj(const std::string& bytes, const std::string& path);
RawMesh parse_off(const std::string& bytes, const std::string& path);
RawMesh parse_stl(const std::string& bytes, const std::string& path);
RawMesh parse_ply_mesh(const std::string& bytes, const std::string& path);

//! Validates, triangulates (fans), welds by exact position, drops unreferenced vertices and
//! faces that collapse, counts defects and builds render vertices with normals.
//! \throw InputError for an empty mesh, non-finite coordinates or out-of-range indices.
Mesh build_mesh(const RawMesh& raw, const std::string& path, const LoadOptions& options = {});

}  // namespace prtsub
