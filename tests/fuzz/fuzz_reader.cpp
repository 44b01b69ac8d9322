// libFuzzer target for one reader, chosen at build time (PRTSUB_FUZZ_READER): the bytes go
// through the reader and, for meshes, the whole builder, as `prtsub bake` would take them. Bad
// input must end in InputError or IoError; anything else (a crash, a sanitizer report, another
// exception, a hang the fuzzer times out) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "prtsub/prt/asset.h"
#include "prtsub/prt/gltf.h"
#include "prtsub/prt/shard.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
#if PRTSUB_FUZZ_READER == 1
    prtsub::build_mesh(prtsub::parse_obj(bytes, "fuzz.obj"), "fuzz.obj");
#elif PRTSUB_FUZZ_READER == 2
    prtsub::build_mesh(prtsub::parse_ply_mesh(bytes, "fuzz.ply"), "fuzz.ply");
#elif PRTSUB_FUZZ_READER == 3
    prtsub::build_mesh(prtsub::parse_off(bytes, "fuzz.off"), "fuzz.off");
#elif PRTSUB_FUZZ_READER == 4
    prtsub::build_mesh(prtsub::parse_stl(bytes, "fuzz.stl"), "fuzz.stl");
#elif PRTSUB_FUZZ_READER == 5
    prtsub::parse_asset(bytes, "fuzz_asset.ply");
#elif PRTSUB_FUZZ_READER == 6
    prtsub::parse_gltf_asset(bytes, "fuzz_asset.glb");
#elif PRTSUB_FUZZ_READER == 7
    prtsub::parse_part(bytes, "fuzz.part");
#else
#error "PRTSUB_FUZZ_READER: 1 obj, 2 ply, 3 off, 4 stl, 5 asset, 6 gltf, 7 part"
#endif
  } catch (const prtsub::InputError&) {
  } catch (const prtsub::IoError&) {
  }
  return 0;
}
