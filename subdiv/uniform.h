// Uniform refinement through OpenSubdiv Far: the baseline adaptive refinement is judged
// against.
#pragma once

#include <string>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

enum class UniformScheme {
  Linear,  //!< each triangle 1→4 at edge midpoints: the same surface as adaptive refinement
  Loop,    //!< Loop subdivision's smooth positions (creases kept sharp)
};

struct UniformOptions {
  int levels = 1;
  UniformScheme scheme = UniformScheme::Linear;
};

//! Refines every face `levels` times (F·4^levels faces). Linear keeps the geometry and
//! interpolates render-vertex normals per crease side (face-varying); Loop moves positions
//! and recomputes normals. source_face is carried from the input.
//! \throw InputError if OpenSubdiv rejects the topology or levels is out of 1..8
Mesh refine_uniform(const Mesh& mesh, const UniformOptions& options);

UniformScheme parse_uniform_scheme(const std::string& name);  //!< linear, loop \throw InputError
const char* uniform_scheme_name(UniformScheme s);

}  // namespace prtsub
