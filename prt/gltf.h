// The PRT asset as glTF 2.0 (.glb or .gltf), for engines and browsers. docs/asset_format.md
// ("glTF") is the contract: attribute names, their types, the metadata in the mesh's extras.
#pragma once

#include <string>

#include "prtsub/prt/asset.h"

namespace prtsub {

//! The source's up axis. glTF is +Y up: a Z-up source is rotated (positions, normals and the
//! SH coefficients together) so that its +Z becomes the file's +Y.
enum class UpAxis { Y, Z };
UpAxis parse_up_axis(const std::string& name);  //!< y, z \throw InputError

struct GltfOptions {
  UpAxis up = UpAxis::Y;  //!< the source's up axis; Y writes the axes unchanged
  //! Transfer as normalized SHORT, coefficient c scaled by max_v |t_vc| (the scales are in the
  //! extras): the error is at most half a step, scale_c / 65534.
  bool quantize = false;
  bool compress = false;  //!< EXT_meshopt_compression (required), through meshoptimizer
};

//! True for a path ending in .glb or .gltf (any case).
bool is_gltf_path(const std::string& path);

//! The rotation taking a Z-up source's axes to glTF's: (x, y, z) -> (x, z, -y).
Eigen::Matrix3d z_up_to_y_up();

//! The file's bytes: a GLB for a `path` ending in .glb, else glTF JSON with the buffer in a
//! data: URI. Arguments as write_asset's. \throw InputError as write_asset
std::string gltf_asset_bytes(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer,
                             const Metadata& metadata, AssetSignal signal, const GltfOptions& options,
                             const RowMatrixX3d& albedo = RowMatrixX3d());

//! Writes the asset through a temporary file renamed into place, like write_asset.
//! \throw InputError as write_asset, IoError if writing fails
void write_gltf_asset(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer,
                      const Metadata& metadata, AssetSignal signal, const GltfOptions& options = {},
                      const RowMatrixX3d& albedo = RowMatrixX3d());

//! Reads a glTF asset prtsub wrote (GLB, or JSON with data: URIs), compressed or not, and
//! returns it in its source's axes (the recorded up rotation undone), as read_asset returns a
//! PLY asset of the same bake. Every count, offset and index is checked against the file; a
//! compressed view may decode to at most 256 times its bytes.
//! \throw InputError naming the file and the first problem found
Asset parse_gltf_asset(const std::string& bytes, const std::string& path);

}  // namespace prtsub
