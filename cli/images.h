// Images for the command-line tool, through a module loaded on first use. OpenImageIO pulls in
// ~260 shared libraries, which cost every process about half a second before main() when the
// tool linked them; only render, diff, compare and environment lights read or write images.
#pragma once

#include <string>

#include "prtsub/prt/asset.h"
#include "prtsub/prt/image_io.h"

namespace prtsub {

//! read_image, by the image module.
//! \throw IoError if the module cannot be loaded, as read_image otherwise
Image cli_read_image(const std::string& path);

//! write_image: encoded by the image module, written here (write_file_atomically).
//! \throw IoError if the module cannot be loaded, as write_image otherwise
void cli_write_image(const std::string& path, const Image& image, const ImageWriteOptions& options = {});

//! The albedo a bake or a reference needs: `spec` with a map's pixels read (by the module).
//! \throw IoError, InputError as cli_read_image
AlbedoSpec cli_load_albedo(AlbedoSpec spec);

//! The coloured albedo over an asset's own surface (its per-vertex albedo, or the map it was
//! baked with through its UVs), or null for a grey asset.
//! \throw InputError naming `path` if the asset records a colour but not the albedo
std::shared_ptr<const AlbedoField> cli_asset_albedo(const Asset& asset, const std::string& path);

}  // namespace prtsub
