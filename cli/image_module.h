// The C interface between the tool and its image module (libprtsub_image_module.so), which
// links OpenImageIO. Exceptions do not cross it: each call returns 0 on success, or 1 (an
// IoError) or 2 (an InputError) with the one-line reason in `error`.
#pragma once

#include <cstddef>
#include <string>

#include "prtsub/prt/lights.h"

extern "C" {
struct PrtsubImageModule {
  int version;  // kPrtsubImageModuleVersion: the tool and the module must agree
  int (*decode)(const char* path, prtsub::Image* out, std::string* error);
  int (*encode)(const char* path, const prtsub::Image* image, double exposure, std::string* out, std::string* error);
};
//! The module's one exported symbol.
const PrtsubImageModule* prtsub_image_module();
}

constexpr int kPrtsubImageModuleVersion = 1;
