// Loading the image module: PRTSUB_IMAGE_MODULE if set, else beside the tool's libraries when
// installed (<prefix>/lib/prtsub/), else where the build put it. Loaded once, on first use, and
// kept for the life of the process.
#include "cli/images.h"

#include <dlfcn.h>
#include <limits.h>
#include <unistd.h>

#include <cstdlib>
#include <mutex>
#include <vector>

#include "cli/image_module.h"
#include "prtsub/prt/output_file.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

std::string executable_dir() {
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) return ".";
  std::string path(buf, static_cast<size_t>(n));
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}

const PrtsubImageModule& image_module() {
  static const PrtsubImageModule* module = nullptr;
  static std::string failure;
  static std::once_flag once;
  std::call_once(once, [] {
    std::vector<std::string> candidates;
    if (const char* env = std::getenv("PRTSUB_IMAGE_MODULE"); env && *env) {
      candidates.push_back(env);
    } else {
      candidates.push_back(executable_dir() + "/../" PRTSUB_INSTALL_LIBDIR "/prtsub/libprtsub_image_module.so");
      candidates.push_back(PRTSUB_IMAGE_MODULE_BUILD_PATH);
    }
    std::string tried;
    for (const std::string& path : candidates) {
      if (::access(path.c_str(), R_OK) != 0) {
        tried += (tried.empty() ? "" : ", ") + path + " (missing)";
        continue;
      }
      void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      const char* why = handle ? nullptr : ::dlerror();
      auto get = handle ? reinterpret_cast<const PrtsubImageModule* (*)()>(::dlsym(handle, "prtsub_image_module")) : nullptr;
      if (get && get()->version == kPrtsubImageModuleVersion) {
        module = get();
        return;
      }
      tried += (tried.empty() ? "" : ", ") + path + " (" + (why ? why : "not a matching prtsub image module") + ")";
    }
    failure = "cannot load the image module (reading and writing images needs it): tried " + tried;
  });
  if (!module) throw IoError(failure);
  return *module;
}

[[noreturn]] void rethrow(int code, const std::string& error) {
  if (code == 2) throw InputError(error);
  throw IoError(error);
}

}  // namespace

Image cli_read_image(const std::string& path) {
  Image image;
  std::string error;
  if (const int code = image_module().decode(path.c_str(), &image, &error)) rethrow(code, error);
  return image;
}

void cli_write_image(const std::string& path, const Image& image, const ImageWriteOptions& options) {
  std::string bytes, error;
  if (const int code = image_module().encode(path.c_str(), &image, options.exposure, &bytes, &error)) rethrow(code, error);
  write_file_atomically(path, bytes);
}

AlbedoSpec cli_load_albedo(AlbedoSpec spec) {
  if (spec.source == AlbedoSource::Map && !spec.image) spec.image = std::make_shared<const Image>(cli_read_image(spec.map));
  return spec;
}

std::shared_ptr<const AlbedoField> cli_asset_albedo(const Asset& asset, const std::string& path) {
  const AssetBounces b = asset_bounces(asset, path);
  if (!b.spec.coloured()) return nullptr;
  if (asset.albedo.rows() == 0) throw InputError(path + ": the metadata names a coloured albedo, but the vertices carry none (albedo_r/g/b)");
  std::shared_ptr<const Image> map;
  if (b.spec.source == AlbedoSource::Map) map = cli_load_albedo(b.spec).image;
  return std::make_shared<const AlbedoField>(asset.triangles, asset.uv, asset.albedo, map);
}

}  // namespace prtsub
