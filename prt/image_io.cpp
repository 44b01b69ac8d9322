// OpenImageIO wrapper. OIIO reports errors through geterror(); every failure becomes an
// IoError naming the file. PNG output is encoded to sRGB here, explicitly: OIIO would
// otherwise quantise float data linearly while tagging the file sRGB (STACK.md).
#include "prtsub/prt/image_io.h"

#include "prtsub/prt/output_file.h"

#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/mesh.h"

namespace prtsub {
namespace {

std::string extension(const std::string& path) {
  size_t dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

double linear_to_srgb(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
}

Image read_image(const std::string& path) {
  if (::access(path.c_str(), R_OK) != 0) throw IoError(path + ": cannot open image (no such readable file)");
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw IoError(path + ": cannot read image (" + OIIO::geterror() + ")");
  const OIIO::ImageSpec& spec = in->spec();
  Image img;
  img.width = spec.width, img.height = spec.height, img.channels = spec.nchannels;
  if (img.width <= 0 || img.height <= 0 || img.channels <= 0) throw InputError(path + ": image has no pixels");
  img.pixels.resize(static_cast<size_t>(img.width) * img.height * img.channels);
  if (!in->read_image(0, 0, 0, img.channels, OIIO::TypeDesc::FLOAT, img.pixels.data()))
    throw IoError(path + ": cannot read image pixels (" + in->geterror() + ")");
  // Integer images (8- and 16-bit PNG, JPEG, TIFF) hold display-encoded sRGB unless the file says
  // it is linear; float images (EXR, HDR) are linear.
  const std::string space = spec.get_string_attribute("oiio:ColorSpace");
  const bool linear_tag = space == "Linear" || space == "linear" || space == "lin_srgb" || space == "scene_linear";
  const bool display = (spec.format == OIIO::TypeDesc::UINT8 || spec.format == OIIO::TypeDesc::UINT16) && !linear_tag;
  in->close();
  if (display) {
    for (size_t i = 0; i < img.pixels.size(); ++i)
      if (img.channels < 4 || i % 4 != 3) img.pixels[i] = static_cast<float>(srgb_to_linear(img.pixels[i]));
  }
  return img;
}

AlbedoSpec read_albedo_map(const std::string& path) {
  AlbedoSpec s;
  s.source = AlbedoSource::Map, s.map = path;
  s.image = std::make_shared<const Image>(read_image(path));
  return s;
}

std::string encode_image(const std::string& path, const Image& img, const ImageWriteOptions& options) {
  const std::string ext = extension(path);
  if (ext != "exr" && ext != "png") throw InputError(path + ": unknown image format (use .exr or .png)");
  // Encoded into memory through OIIO's I/O proxy; write_image then writes it like every other
  // output (write_file_atomically: a temporary file renamed into place, devices in place, every
  // error checked), so an image follows the same rules as an asset or a report.
  std::vector<unsigned char> encoded;
  OIIO::Filesystem::IOVecOutput proxy(encoded);
  auto out = OIIO::ImageOutput::create("image." + ext);
  if (!out || !out->supports("ioproxy")) throw IoError(path + ": no in-memory image writer (" + OIIO::geterror() + ")");
  out->set_ioproxy(&proxy);
  bool ok;
  if (ext == "exr") {
    OIIO::ImageSpec spec(img.width, img.height, img.channels, OIIO::TypeDesc::FLOAT);
    ok = out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, img.pixels.data());
  } else {
    OIIO::ImageSpec spec(img.width, img.height, img.channels, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    std::vector<unsigned char> bytes(img.pixels.size());
    for (size_t i = 0; i < bytes.size(); ++i) {
      const bool alpha = img.channels == 4 && i % 4 == 3;
      double v = alpha ? std::clamp<double>(img.pixels[i], 0, 1) : linear_to_srgb(options.exposure * img.pixels[i]);
      bytes[i] = static_cast<unsigned char>(std::lround(255 * (std::isfinite(v) ? v : 0.0)));
    }
    ok = out->open(path, spec) && out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
  }
  const std::string err = ok ? "" : out->geterror();
  ok = out->close() && ok;
  if (!ok) throw IoError(path + ": cannot encode image (" + (err.empty() ? out->geterror() : err) + ")");
  return std::string(encoded.begin(), encoded.end());
}

void write_image(const std::string& path, const Image& img, const ImageWriteOptions& options) {
  write_file_atomically(path, encode_image(path, img, options));
}

}  // namespace prtsub
