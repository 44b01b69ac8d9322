// Baked glTF assets against the Khronos validator (tests/gltf/validate.mjs, npm packages pinned
// in tests/gltf/package-lock.json), every option combination the tool writes. Compressed files
// are also decoded by meshoptimizer's reference JavaScript decoder; tinygltf must then read
// exactly the bytes of the same bake written uncompressed. Needs Node.js and `npm ci` in
// tests/gltf (.ci/deps does both): skipped without them on a user's machine, failed in CI.
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "cli_helpers.h"

namespace prtsub {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

tinygltf::Model load(const std::string& path) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool glb = path.substr(path.size() - 4) == ".glb";
  EXPECT_TRUE(glb ? loader.LoadBinaryFromFile(&model, &err, &warn, path) : loader.LoadASCIIFromFile(&model, &err, &warn, path))
      << path << ": " << err;
  return model;
}

// The bytes accessor `index` covers, element by element without the view's stride padding.
std::string accessor_bytes(const tinygltf::Model& m, int index) {
  const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(index)];
  const tinygltf::BufferView& v = m.bufferViews[static_cast<size_t>(a.bufferView)];
  const size_t size = static_cast<size_t>(tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType)) *
                                          tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type)));
  const size_t stride = a.ByteStride(v) > 0 ? static_cast<size_t>(a.ByteStride(v)) : size;
  const auto* base = reinterpret_cast<const char*>(m.buffers[static_cast<size_t>(v.buffer)].data.data()) + v.byteOffset + a.byteOffset;
  std::string out;
  for (size_t i = 0; i < a.count; ++i) out.append(base + i * stride, size);
  return out;
}

TEST(GltfValidator, EveryBakedVariantIsValidAndCompressedFilesDecodeToTheUncompressedBytes) {
  const std::string tools = PRTSUB_GLTF_TOOLS;
  const bool have = std::system("node --version > /dev/null 2>&1") == 0 && test::file_exists(tools + "/node_modules/gltf-validator/package.json") &&
                    test::file_exists(tools + "/node_modules/meshoptimizer/package.json");
  if (!have) {
    if (std::getenv("CI")) FAIL() << "CI must validate glTF assets: Node.js or `npm ci` in " << tools << " is missing (.ci/deps installs both)";
    GTEST_SKIP() << "Node.js or the pinned validator is missing: run `npm ci` in " << tools;
  }
  test::TempDir dir;
  const std::string mesh = std::string(PRTSUB_EXAMPLES) + "/spot/spot_control_mesh.obj";
  const std::vector<std::pair<std::string, std::vector<std::string>>> variants = {
      {"a.glb", {}},
      {"a.gltf", {}},
      {"q.gltf", {"--quantize"}},
      {"c.glb", {"--compress"}},
      {"qc.glb", {"--quantize", "--compress"}},
      {"z.glb", {"--up", "z", "--order", "5"}},
      {"ao.glb", {"--signal", "ao"}},
      {"aoc.glb", {"--signal", "ao", "--compress"}},
      {"rgb.glb", {"--bounces", "1", "--albedo", "0.9,0.5,0.2", "--quantize", "--compress"}},
      {"sg.glb", {"--basis", "sg:9", "--up", "z", "--quantize", "--compress"}},
  };
  std::string files;
  for (const auto& [name, extra] : variants) {
    std::vector<std::string> args = {"bake", mesh, "-o", dir.path(name), "--rays", "16", "--fit", "point"};
    args.insert(args.end(), extra.begin(), extra.end());
    ASSERT_EQ(test::run_prtsub(args), 0) << name;
    files += " " + dir.path(name);
  }
  const std::string log = dir.path("validator.txt");
  const int rc = std::system(("node " + tools + "/validate.mjs --decoded " + dir.path("") + files + " > " + log + " 2>&1").c_str());
  const std::string out = read_text(log);
  EXPECT_EQ(rc, 0) << out;
  for (const auto& [name, extra] : variants) EXPECT_NE(out.find(dir.path(name) + ": 0 errors, 0 warnings"), std::string::npos) << out;
  EXPECT_EQ(out.find("error "), std::string::npos) << out;

  // The reference decoder's output, read by tinygltf, holds the uncompressed file's bytes.
  for (const auto& [decoded, plain] : std::vector<std::pair<std::string, std::string>>{
           {"c.decoded.glb", "a.glb"}, {"qc.decoded.glb", "q.gltf"}, {"aoc.decoded.glb", "ao.glb"}}) {
    const tinygltf::Model d = load(dir.path(decoded)), p = load(dir.path(plain));
    const auto& da = d.meshes.at(0).primitives.at(0).attributes;
    const auto& pa = p.meshes.at(0).primitives.at(0).attributes;
    ASSERT_EQ(da.size(), pa.size()) << decoded;
    for (const auto& [attribute, index] : pa) {
      ASSERT_EQ(da.count(attribute), 1u) << decoded << " " << attribute;
      EXPECT_EQ(accessor_bytes(d, da.at(attribute)), accessor_bytes(p, index)) << decoded << " " << attribute;
    }
    // The index codec may start a triangle at another corner; the winding and the order stay.
    const std::string di = accessor_bytes(d, d.meshes[0].primitives[0].indices), pi = accessor_bytes(p, p.meshes[0].primitives[0].indices);
    ASSERT_EQ(di.size(), pi.size()) << decoded;
    size_t rotated = 0;
    for (size_t t = 0; t < di.size(); t += 12) {
      const std::string a = di.substr(t, 12), b = pi.substr(t, 12);
      const bool same = a == b || a == b.substr(4) + b.substr(0, 4) || a == b.substr(8) + b.substr(0, 8);
      EXPECT_TRUE(same) << decoded << " triangle " << t / 12;
      rotated += a != b;
    }
    std::printf("%s: %zu of %zu triangles start at another corner\n", decoded.c_str(), rotated, di.size() / 12);
    const int sd = d.meshes[0].extras.Get("source_face_accessor").GetNumberAsInt();
    const int sp = p.meshes[0].extras.Get("source_face_accessor").GetNumberAsInt();
    EXPECT_EQ(accessor_bytes(d, sd), accessor_bytes(p, sp)) << decoded;
  }
}

}  // namespace
}  // namespace prtsub
