// Reading and writing images. The only translation unit that includes OpenImageIO.
#pragma once

#include <string>

#include "prtsub/prt/albedo.h"
#include "prtsub/prt/lights.h"

namespace prtsub {

//! Reads any image OpenImageIO can (EXR, HDR, PNG, ...) as linear float, all channels.
//! 8- and 16-bit formats are converted from sRGB to linear (alpha kept), unless the file tags
//! itself linear.
//! \throw IoError if missing or unreadable, InputError if it has no pixels
Image read_image(const std::string& path);

struct ImageWriteOptions {
  double exposure = 1.0;  //!< PNG only: linear values are multiplied by this before encoding
};

//! Writes by extension: .exr is linear float (all channels as given); .png is tone-mapped
//! 8-bit sRGB: clamp(exposure · v, 0, 1), then the sRGB curve; alpha is kept linear.
//! Goes through a temporary file renamed into place (write_file_atomically).
//! \throw IoError, InputError for an unknown extension
void write_image(const std::string& path, const Image& image, const ImageWriteOptions& options = {});

//! The file write_image would write, in memory (the format from path's extension).
//! \throw IoError, InputError for an unknown extension
std::string encode_image(const std::string& path, const Image& image, const ImageWriteOptions& options = {});

//! An albedo from a diffuse texture: read_image's pixels (8-bit sRGB decoded, float linear)
//! behind spec.image, for AlbedoField. \throw IoError, InputError as read_image
AlbedoSpec read_albedo_map(const std::string& path);

//! The sRGB encoding of a linear value in [0, 1] (IEC 61966-2-1).
double linear_to_srgb(double v);

}  // namespace prtsub
