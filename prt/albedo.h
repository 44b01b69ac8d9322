// The diffuse albedo of the surfaces light bounces off: one grey or RGB constant, the input's
// vertex colours, or a texture read through the UVs. docs/sh_convention.md, "Colour", is the
// contract for how it enters the transfer.
#pragma once

#include <memory>
#include <string>

#include "prtsub/prt/lights.h"
#include "prtsub/subdiv/mesh.h"

namespace prtsub {

enum class AlbedoSource { Constant, Vertex, Map };

struct AlbedoSpec {
  AlbedoSource source = AlbedoSource::Constant;
  Eigen::Vector3d constant{0.8, 0.8, 0.8};  //!< linear RGB in [0, 1] (Constant)
  std::string map;                          //!< the image's path (Map)
  //! The map's pixels, linear (Map): read by read_albedo_map (image_io.h), since prt/ reads no
  //! image files
  std::shared_ptr<const Image> image;
  //! Whether it can differ between channels: anything but a grey constant. A coloured albedo
  //! gives RGB transfer once light bounces.
  bool coloured() const;
};

//! "A" (grey), "R,G,B" (linear, each in [0, 1]) or "vertex" (the input's vertex colours).
//! \throw InputError naming the problem
AlbedoSpec parse_albedo(const std::string& text);

//! What the asset records: "0.8", "0.9,0.5,0.2", "vertex colours (sRGB decoded)", "map PATH ...".
std::string albedo_description(const AlbedoSpec& spec);

//! The albedo over one mesh's surface, at its render vertices and at any point of a face.
class AlbedoField {
 public:
  //! \throw InputError when the source needs what the mesh lacks (vertex colours, UVs), or the
  //!        map was not read, has fewer than three channels or values outside [0, 1]
  AlbedoField(const Mesh& mesh, const AlbedoSpec& spec);
  //! The same over an asset's surface: its triangles and UVs, the albedo it stores per vertex,
  //! and the map (null unless the albedo came from one; then `uv` must have a row per vertex).
  //! \throw InputError for shapes that do not match
  AlbedoField(const std::vector<Triangle>& triangles, const RowMatrixX2d& uv, const RowMatrixX3d& vertex_albedo,
              std::shared_ptr<const Image> map);

  //! At the point of face f with Embree's barycentrics (u, v): corner 0 weighs 1 − u − v. A map
  //! is sampled at the point's interpolated UV, not at the corners.
  Eigen::Vector3d at(uint32_t face, double u, double v) const;
  //! #V by 3: at each render vertex (a map sampled at its UV)
  const RowMatrixX3d& vertices() const { return vertex_; }
  const AlbedoSpec& spec() const { return spec_; }

 private:
  AlbedoSpec spec_;
  std::vector<Triangle> triangles_;
  RowMatrixX2d uv_;
  RowMatrixX3d vertex_;
  std::shared_ptr<const Image> map_;
};

//! A map's linear RGB at texture coordinate (u, v): bilinear, repeating outside [0, 1], v = 0 at
//! the image's bottom row (the OBJ and PLY convention).
Eigen::Vector3d sample_albedo_map(const Image& map, double u, double v);

}  // namespace prtsub
