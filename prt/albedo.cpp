// Albedo for interreflection. A bounce at a hit point h carries ρ(h), so what matters is the
// albedo at any point of a face: vertex colours (and constants) are interpolated
// barycentrically, as the asset's transfer is; a map is sampled at the hit's own UV, so a
// texture's detail inside a large triangle still colours the light it reflects. The receiver's
// own albedo is not folded into its transfer (the renderer multiplies it in, as it does for a
// grey asset), so a texture stays sharp below vertex resolution; the asset stores the albedo at
// each vertex for renderers that have no texture.
//
// Colours in files are display colours: vertex colours (PLY red/green/blue, OBJ `v x y z r g b`)
// and 8- and 16-bit images are decoded from sRGB to linear (subdiv/mesh_io, image_io); float images
// (EXR, HDR) are taken as linear.
#include "prtsub/prt/albedo.h"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <utility>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

bool AlbedoSpec::coloured() const {
  return source != AlbedoSource::Constant || constant.x() != constant.y() || constant.y() != constant.z();
}

namespace {

double parse_unit(const std::string& item, const std::string& text) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(item, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != item.size() || !std::isfinite(v))
    throw InputError("albedo '" + text + "': '" + item + "' is not a number (give A, R,G,B or vertex)");
  if (v < 0 || v > 1) throw InputError("albedo '" + text + "': " + item + " is outside [0, 1]");
  return v;
}

}  // namespace

AlbedoSpec parse_albedo(const std::string& text) {
  AlbedoSpec s;
  if (text == "vertex") {
    s.source = AlbedoSource::Vertex;
    return s;
  }
  std::vector<std::string> items;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) items.push_back(item);
  if (items.size() == 1) s.constant.setConstant(parse_unit(items[0], text));
  else if (items.size() == 3) {
    // Parsed before assigning: a throw inside Eigen's comma initializer would trip its assertion.
    const double r = parse_unit(items[0], text), g = parse_unit(items[1], text), b = parse_unit(items[2], text);
    s.constant = Eigen::Vector3d(r, g, b);
  }
  else throw InputError("albedo '" + text + "': give one value A, three values R,G,B (linear) or vertex");
  return s;
}

std::string albedo_description(const AlbedoSpec& s) {
  char buf[96];
  switch (s.source) {
    case AlbedoSource::Vertex: return "vertex colours (sRGB decoded to linear)";
    case AlbedoSource::Map: return "map " + s.map + " (through the UVs; 8- and 16-bit sRGB decoded to linear)";
    case AlbedoSource::Constant: break;
  }
  if (!s.coloured()) std::snprintf(buf, sizeof buf, "%.6g", s.constant.x());
  else std::snprintf(buf, sizeof buf, "%.6g,%.6g,%.6g", s.constant.x(), s.constant.y(), s.constant.z());
  return buf;
}

Eigen::Vector3d sample_albedo_map(const Image& map, double u, double v) {
  const double x = (u - std::floor(u)) * map.width - 0.5, y = (1 - (v - std::floor(v))) * map.height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y), ax = x - fx, ay = y - fy;
  auto wrap = [](long i, int n) { return static_cast<int>(((i % n) + n) % n); };
  const int x0 = wrap(long(fx), map.width), x1 = wrap(long(fx) + 1, map.width);
  const int y0 = wrap(long(fy), map.height), y1 = wrap(long(fy) + 1, map.height);
  Eigen::Vector3d c;
  for (int k = 0; k < 3; ++k)
    c[k] = (1 - ay) * ((1 - ax) * map.at(x0, y0, k) + ax * map.at(x1, y0, k)) + ay * ((1 - ax) * map.at(x0, y1, k) + ax * map.at(x1, y1, k));
  return c;
}

AlbedoField::AlbedoField(const Mesh& mesh, const AlbedoSpec& spec) : spec_(spec), triangles_(mesh.triangles) {
  const auto V = static_cast<Eigen::Index>(mesh.num_vertices());
  switch (spec.source) {
    case AlbedoSource::Constant:
      vertex_ = spec.constant.transpose().replicate(V, 1);
      break;
    case AlbedoSource::Vertex:
      if (!mesh.has_colors()) throw InputError("albedo from vertex colours, but the mesh has none (PLY red/green/blue, OBJ v x y z r g b)");
      vertex_ = mesh.colors;
      break;
    case AlbedoSource::Map: {
      if (!mesh.has_uv()) throw InputError("albedo map " + spec.map + " needs texture coordinates, and the mesh has none");
      if (!spec.image) throw InputError(spec.map + ": the albedo map was not read (read_albedo_map)");
      auto image = std::make_shared<Image>(*spec.image);
      if (image->channels < 3) throw InputError(spec.map + ": an albedo map needs three colour channels, the image has " + std::to_string(image->channels));
      for (int y = 0; y < image->height; ++y)
        for (int x = 0; x < image->width; ++x)
          for (int k = 0; k < 3; ++k) {
            const float a = image->at(x, y, k);
            if (!(a >= 0 && a <= 1.0001f))
              throw InputError(spec.map + ": pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") has an albedo of " + std::to_string(a) +
                               ", outside [0, 1]");
            image->at(x, y, k) = std::min(a, 1.0f);
          }
      map_ = image;
      uv_ = mesh.uv;
      vertex_.resize(V, 3);
      for (Eigen::Index i = 0; i < V; ++i) vertex_.row(i) = sample_albedo_map(*map_, mesh.uv(i, 0), mesh.uv(i, 1)).transpose();
      break;
    }
  }
}

AlbedoField::AlbedoField(const std::vector<Triangle>& triangles, const RowMatrixX2d& uv, const RowMatrixX3d& vertex_albedo,
                         std::shared_ptr<const Image> map)
    : triangles_(triangles), uv_(uv), vertex_(vertex_albedo), map_(std::move(map)) {
  if (map_) spec_.source = AlbedoSource::Map;
  else spec_.source = AlbedoSource::Vertex;
  if (map_ && uv_.rows() != vertex_.rows()) throw InputError("albedo: a map needs a UV at every vertex");
  if (map_ && map_->channels < 3) throw InputError("albedo: a map needs three colour channels");
  for (const Triangle& t : triangles_)
    for (uint32_t c : t)
      if (c >= vertex_.rows()) throw InputError("albedo: a triangle indexes past the vertices' albedo");
}

Eigen::Vector3d AlbedoField::at(uint32_t face, double u, double v) const {
  const Triangle& t = triangles_[face];
  const double w0 = 1 - u - v;
  if (map_) {
    const Eigen::RowVector2d uv = w0 * uv_.row(t[0]) + u * uv_.row(t[1]) + v * uv_.row(t[2]);
    return sample_albedo_map(*map_, uv.x(), uv.y());
  }
  return (w0 * vertex_.row(t[0]) + u * vertex_.row(t[1]) + v * vertex_.row(t[2])).transpose();
}

}  // namespace prtsub
