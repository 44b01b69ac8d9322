// The PRT asset: a binary little-endian PLY with per-vertex transfer. docs/asset_format.md
// is the contract with consumers.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "subdiv/mesh.h"

namespace prtsub {

using Metadata = std::vector<std::pair<std::string, std::string>>;

//! An asset as read back: render vertices with their transfer.
struct Asset {
  RowMatrixX3d positions;             //!< #V by 3
  RowMatrixX3d normals;               //!< #V by 3
  RowMatrixXd transfer;               //!< #V by N²
  std::vector<Triangle> triangles;    //!< #F
  std::vector<uint32_t> source_face;  //!< #F
  Metadata metadata;                  //!< "key value" comment lines, in order
  int order = 0;
};

//! The comment lines stating the SH convention, written into every asset.
Metadata sh_convention_metadata(int order);

//! Writes mesh + transfer to `path` through a temporary file renamed into place, so a failed
//! run leaves nothing behind.
//! \param transfer #V by N², V = mesh.num_vertices()
//! \throw InputError if transfer holds NaN/Inf or has the wrong shape, IoError if writing fails
void write_asset(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer,
                 const Metadata& metadata);

//! Reads an asset and checks it: sizes consistent, indices in range, no NaN/Inf.
//! \throw InputError naming the file and the first problem found
Asset read_asset(const std::string& path);

//! Writes bytes to path atomically (temporary file in the same directory, then rename).
void write_file_atomically(const std::string& path, const std::string& bytes);

}  // namespace prtsub
