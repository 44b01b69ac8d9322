// The image module: read_image and encode_image behind the C interface of image_module.h.
#include "cli/image_module.h"

#include "prtsub/prt/image_io.h"
#include "prtsub/subdiv/exceptions.h"

namespace {

template <class F>
int guarded(std::string* error, F&& f) {
  try {
    f();
    return 0;
  } catch (const prtsub::InputError& e) {
    *error = e.what();
    return 2;
  } catch (const std::exception& e) {
    *error = e.what();
    return 1;
  }
}

int decode(const char* path, prtsub::Image* out, std::string* error) {
  return guarded(error, [&] { *out = prtsub::read_image(path); });
}

int encode(const char* path, const prtsub::Image* image, double exposure, std::string* out, std::string* error) {
  return guarded(error, [&] { *out = prtsub::encode_image(path, *image, prtsub::ImageWriteOptions{exposure}); });
}

const PrtsubImageModule kModule = {kPrtsubImageModuleVersion, decode, encode};

}  // namespace

extern "C" __attribute__((visibility("default"))) const PrtsubImageModule* prtsub_image_module() { return &kModule; }
