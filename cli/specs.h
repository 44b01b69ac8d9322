// The command line's little languages: light specs, light rotations and camera specs. Each
// mistake is a UsageError naming the option (exit 2); a light's file is read with read_image,
// so a missing environment map is an IoError (exit 1) like any other missing file.
#pragma once

#include <string>

#include "cli/args.h"
#include "prtsub/prt/lights.h"
#include "prtsub/prt/render.h"

namespace prtsub {

//! env:PATH, sh:c0,c1,..., sun:X,Y,Z[,RADIUS_DEG], sky[:X,Y,Z] (the up direction),
//! random:SEED, const:V or const:R,G,B, for `option` (named in errors).
//! \throw UsageError naming the option and the spec, IoError for an unreadable map
ShLight parse_light(const std::string& spec, int order, const std::string& option = "--light");

//! Several specs added together. \pre specs is not empty
ShLight parse_lights(const std::vector<std::string>& specs, int order, const std::string& option = "--light");

//! AXIS,DEG with AXIS x, y, z or three numbers X,Y,Z. \throw UsageError
Eigen::Matrix3d parse_rotation(const std::string& spec, const std::string& option = "--light-rotate");

//! eye=X,Y,Z:target=X,Y,Z[:up=X,Y,Z][:fov=DEG]. \throw UsageError
Camera parse_camera(const std::string& spec, const std::string& option = "--camera");

}  // namespace prtsub
