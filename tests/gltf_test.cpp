// glTF assets, read back two ways: by tinygltf (Debian's libtinygltf, an independent reader), which
// must find the documented layout and the same values as the PLY asset of the same bake, and by
// prtsub's own reader, which every command uses. Bad files must fail with one InputError.
#include "prtsub/prt/gltf.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "helpers.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/lights.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

// A real bake of a small scene with UVs: a UV-seamed square over a sphere, order 3.
struct Baked {
  Mesh mesh;
  RowMatrixXd transfer;
  Metadata metadata;
};

const Baked& baked() {
  static const Baked b = [] {
    // A pyramid standing on the square shadows it, so the transfer varies from vertex to vertex.
    const std::string pyramid = "v 0.3 0.3 0.05\nv 0.7 0.3 0.05\nv 0.5 0.7 0.05\nv 0.5 0.5 0.6\n"
                                "f 5/1 6/1 8/1\nf 6/1 7/1 8/1\nf 7/1 5/1 8/1\n";
    RawMesh square = parse_obj(test::seam_square_obj() + pyramid, "seam.obj");
    Mesh mesh = build_mesh(square, "seam.obj");
    BakeOptions o;
    o.transfer.order = 3, o.transfer.rays = 16;
    o.fit.method = FitMethod::Point;
    BakeResult r = bake(mesh, o);
    return Baked{r.mesh, r.transfer, r.metadata};
  }();
  return b;
}

tinygltf::Model load_tiny(const std::string& path) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = path.size() > 4 && path.substr(path.size() - 4) == ".glb" ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                                                                              : loader.LoadASCIIFromFile(&model, &err, &warn, path);
  EXPECT_TRUE(ok) << err;
  return model;
}

// Accessor `index` as doubles, through tinygltf's views; normalized SHORT as q / 32767.
std::vector<double> tiny_values(const tinygltf::Model& m, int index, int& components) {
  const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(index)];
  const tinygltf::BufferView& v = m.bufferViews[static_cast<size_t>(a.bufferView)];
  const unsigned char* base = m.buffers[static_cast<size_t>(v.buffer)].data.data() + v.byteOffset + a.byteOffset;
  components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
  const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
  const size_t stride = a.ByteStride(v) > 0 ? static_cast<size_t>(a.ByteStride(v)) : static_cast<size_t>(size * components);
  std::vector<double> out;
  for (size_t i = 0; i < a.count; ++i)
    for (int c = 0; c < components; ++c) {
      const unsigned char* p = base + i * stride + static_cast<size_t>(c * size);
      if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) {
        float f;
        std::memcpy(&f, p, 4);
        out.push_back(f);
      } else if (a.componentType == TINYGLTF_COMPONENT_TYPE_SHORT) {
        int16_t s;
        std::memcpy(&s, p, 2);
        out.push_back(a.normalized ? std::max(s / 32767.0, -1.0) : s);
      } else if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
        uint16_t u;
        std::memcpy(&u, p, 2);
        out.push_back(a.normalized ? u / 65535.0 : u);
      } else {
        uint32_t u;
        std::memcpy(&u, p, 4);
        out.push_back(u);
      }
    }
  return out;
}

std::vector<double> tiny_attribute(const tinygltf::Model& m, const std::string& name, int& components) {
  const auto& attrs = m.meshes[0].primitives[0].attributes;
  const auto it = attrs.find(name);
  EXPECT_NE(it, attrs.end()) << name;
  return it == attrs.end() ? std::vector<double>{} : tiny_values(m, it->second, components);
}

// The file's transfer as #V by K, its _PRT_k VEC4s unpacked (scaled when quantized).
RowMatrixXd tiny_transfer(const tinygltf::Model& m, int K) {
  const tinygltf::Value& extras = m.meshes[0].extras;
  std::vector<double> scale(static_cast<size_t>(K), 1.0);
  if (extras.Has("quantization"))
    for (int c = 0; c < K; ++c) scale[static_cast<size_t>(c)] = extras.Get("quantization").Get("scale").Get(c).GetNumberAsDouble();
  RowMatrixXd t;
  for (int k = 0; 4 * k < K; ++k) {
    int comps = 0;
    const std::vector<double> v = tiny_attribute(m, "_PRT_" + std::to_string(k), comps);
    EXPECT_EQ(comps, 4);
    if (k == 0) t.resize(static_cast<Eigen::Index>(v.size() / 4), K);
    for (Eigen::Index i = 0; i < t.rows(); ++i)
      for (int c = 4 * k; c < 4 * k + 4; ++c) {
        const double x = v[static_cast<size_t>(i) * 4 + static_cast<size_t>(c - 4 * k)];
        if (c < K) t(i, c) = scale[static_cast<size_t>(c)] * x;
        else EXPECT_EQ(x, 0.0) << "padding";
      }
  }
  return t;
}

TEST(Gltf, AnIndependentReaderFindsThePlyAssetsValuesInTheDocumentedLayout) {
  test::TempDir dir;
  const Baked& b = baked();
  write_asset(dir.path("a.ply"), b.mesh, b.transfer, b.metadata);
  const Asset ply = read_asset(dir.path("a.ply"));
  for (const char* name : {"a.glb", "a.gltf"}) {
    write_gltf_asset(dir.path(name), b.mesh, b.transfer, b.metadata, AssetSignal::Transfer);
    const tinygltf::Model m = load_tiny(dir.path(name));
    ASSERT_EQ(m.meshes.size(), 1u);
    const tinygltf::Primitive& p = m.meshes[0].primitives[0];
    EXPECT_EQ(p.mode, TINYGLTF_MODE_TRIANGLES);
    // 9 coefficients: _PRT_0, _PRT_1 and _PRT_2 (t8 and three zeros), nothing more.
    for (const char* a : {"POSITION", "NORMAL", "TEXCOORD_0", "_PRT_0", "_PRT_1", "_PRT_2"}) EXPECT_EQ(p.attributes.count(a), 1u) << a;
    EXPECT_EQ(p.attributes.size(), 6u);
    int c = 0;
    const std::vector<double> pos = tiny_attribute(m, "POSITION", c);
    ASSERT_EQ(pos.size(), 3 * static_cast<size_t>(ply.positions.rows()));
    for (Eigen::Index i = 0; i < ply.positions.rows(); ++i)
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(pos[static_cast<size_t>(3 * i + k)], ply.positions(i, k));
        EXPECT_EQ(tiny_attribute(m, "NORMAL", c)[static_cast<size_t>(3 * i + k)], ply.normals(i, k));
      }
    const std::vector<double> uv = tiny_attribute(m, "TEXCOORD_0", c);
    for (Eigen::Index i = 0; i < ply.uv.rows(); ++i) {
      EXPECT_EQ(uv[static_cast<size_t>(2 * i)], ply.uv(i, 0));
      EXPECT_NEAR(uv[static_cast<size_t>(2 * i + 1)], 1.0 - ply.uv(i, 1), 1e-7);  // glTF's v runs down
    }
    EXPECT_EQ((tiny_transfer(m, 9) - ply.transfer).cwiseAbs().maxCoeff(), 0.0);
    const std::vector<double> idx = tiny_values(m, p.indices, c);
    ASSERT_EQ(idx.size(), 3 * ply.triangles.size());
    for (size_t f = 0; f < ply.triangles.size(); ++f)
      for (size_t k = 0; k < 3; ++k) EXPECT_EQ(idx[3 * f + k], ply.triangles[f][k]);
    const tinygltf::Value& extras = m.meshes[0].extras;
    EXPECT_EQ(extras.Get("sh_order").GetNumberAsInt(), 3);
    EXPECT_EQ(extras.Get("signal").Get<std::string>(), "transfer");
    const std::vector<double> src = tiny_values(m, extras.Get("source_face_accessor").GetNumberAsInt(), c);
    for (size_t f = 0; f < ply.source_face.size(); ++f) EXPECT_EQ(src[f], ply.source_face[f]);
    // prtsub's own reader gives back the PLY asset, metadata and all.
    const Asset back = read_asset(dir.path(name));
    EXPECT_EQ((back.transfer - ply.transfer).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((back.positions - ply.positions).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_LT((back.uv - ply.uv).cwiseAbs().maxCoeff(), 1e-7);
    EXPECT_EQ(back.triangles, ply.triangles);
    EXPECT_EQ(back.source_face, ply.source_face);
    EXPECT_EQ(back.metadata, ply.metadata);
  }
}

TEST(Gltf, QuantizedTransferIsWithinHalfAStepOfEveryCoefficient) {
  test::TempDir dir;
  const Baked& b = baked();
  GltfOptions o;
  o.quantize = true;
  write_gltf_asset(dir.path("q.glb"), b.mesh, b.transfer, b.metadata, AssetSignal::Transfer, o);
  const tinygltf::Model m = load_tiny(dir.path("q.glb"));
  const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(m.meshes[0].primitives[0].attributes.at("_PRT_0"))];
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_SHORT);
  EXPECT_TRUE(a.normalized);
  const RowMatrixXd t = tiny_transfer(m, 9);
  const RowMatrixXd ours = read_asset(dir.path("q.glb")).transfer;
  for (Eigen::Index c = 0; c < 9; ++c) {
    const double scale = b.transfer.col(c).cwiseAbs().maxCoeff();
    const double half_step = 0.5 * scale / 32767 * (1 + 1e-6) + 1e-7 * scale;  // + float rounding of the scale
    EXPECT_LE((t.col(c) - b.transfer.col(c)).cwiseAbs().maxCoeff(), half_step) << c;
    EXPECT_LE((ours.col(c) - b.transfer.col(c)).cwiseAbs().maxCoeff(), half_step) << c;
  }
  EXPECT_GT((t - b.transfer).cwiseAbs().maxCoeff(), 0.0) << "quantization that loses nothing is not quantizing";
}

TEST(Gltf, AZUpSourceRelightsTheSameUnderTheSameLightInGltfsAxes) {
  test::TempDir dir;
  const Baked& b = baked();
  GltfOptions o;
  o.up = UpAxis::Z;
  write_gltf_asset(dir.path("z.glb"), b.mesh, b.transfer, b.metadata, AssetSignal::Transfer, o);
  const tinygltf::Model m = load_tiny(dir.path("z.glb"));
  const RowMatrixXd t = tiny_transfer(m, 9);
  int c = 0;
  const std::vector<double> pos = tiny_attribute(m, "POSITION", c), nrm = tiny_attribute(m, "NORMAL", c);
  const RowMatrixX3d src = vertex_positions(b.mesh);
  for (Eigen::Index i = 0; i < src.rows(); ++i) {  // (x, y, z) -> (x, z, -y): the source's +Z is the file's +Y
    EXPECT_NEAR(pos[static_cast<size_t>(3 * i)], src(i, 0), 1e-6);
    EXPECT_NEAR(pos[static_cast<size_t>(3 * i + 1)], src(i, 2), 1e-6);
    EXPECT_NEAR(pos[static_cast<size_t>(3 * i + 2)], -src(i, 1), 1e-6);
    EXPECT_NEAR(nrm[static_cast<size_t>(3 * i + 1)], b.mesh.normals(i, 2), 1e-6);
  }
  // A light from direction d in the source is a light from R·d in the file: radiance at every
  // vertex, Σ y_i(dir) t_i, must agree. Evaluated from the basis alone, not sh_rotation.
  const Eigen::Matrix3d R = z_up_to_y_up();
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const Eigen::Vector3d d = test::random_direction(seed);
    const Eigen::VectorXd y_src = sh_eval(3, d), y_file = sh_eval(3, R * d);
    const Eigen::VectorXd l_src = b.transfer * y_src, l_file = t * y_file;
    EXPECT_LT((l_src - l_file).cwiseAbs().maxCoeff(), 1e-5 * (1 + l_src.cwiseAbs().maxCoeff())) << seed;
  }
  // prtsub's reader undoes the rotation: the asset comes back in the source's axes.
  const Asset back = read_asset(dir.path("z.glb"));
  EXPECT_LT((back.positions - src).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((back.transfer - b.transfer).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(Gltf, CompressionDecodesToExactlyTheUncompressedAsset) {
  test::TempDir dir;
  const Baked& b = baked();
  GltfOptions o;
  write_gltf_asset(dir.path("plain.glb"), b.mesh, b.transfer, b.metadata, AssetSignal::Transfer, o);
  o.compress = true;
  for (const char* name : {"c.glb", "c.gltf"}) {
    write_gltf_asset(dir.path(name), b.mesh, b.transfer, b.metadata, AssetSignal::Transfer, o);
    const std::string bytes = read_file_bytes(dir.path(name));
    EXPECT_NE(bytes.find("\"extensionsRequired\":[\"EXT_meshopt_compression\"]"), std::string::npos);
    const Asset plain = read_asset(dir.path("plain.glb")), c = read_asset(dir.path(name));
    EXPECT_EQ(c.positions, plain.positions);
    EXPECT_EQ(c.normals, plain.normals);
    EXPECT_EQ(c.uv, plain.uv);
    EXPECT_EQ(c.transfer, plain.transfer);
    // meshoptimizer's index codec may start a triangle at another corner, keeping its winding.
    ASSERT_EQ(c.triangles.size(), plain.triangles.size());
    for (size_t f = 0; f < c.triangles.size(); ++f) {
      Triangle t = c.triangles[f];
      for (int turn = 0; turn < 2 && t != plain.triangles[f]; ++turn) std::rotate(t.begin(), t.begin() + 1, t.end());
      EXPECT_EQ(t, plain.triangles[f]) << f;
    }
    EXPECT_EQ(c.source_face, plain.source_face);
  }
}

TEST(Gltf, AoGoesInColor0AsNormalizedShortsAndInAFloatAttribute) {
  test::TempDir dir;
  Mesh mesh = test::build(test::cube());
  RowMatrixXd t0(static_cast<Eigen::Index>(mesh.num_vertices()), 1);
  for (Eigen::Index v = 0; v < t0.rows(); ++v) t0(v, 0) = (static_cast<double>(v) / static_cast<double>(t0.rows())) / kAoPerT0;
  write_gltf_asset(dir.path("ao.glb"), mesh, t0, ao_metadata(), AssetSignal::Ao);
  const tinygltf::Model m = load_tiny(dir.path("ao.glb"));
  const tinygltf::Accessor& colour = m.accessors[static_cast<size_t>(m.meshes[0].primitives[0].attributes.at("COLOR_0"))];
  EXPECT_EQ(colour.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  EXPECT_TRUE(colour.normalized);
  int c = 0;
  const std::vector<double> rgba = tiny_attribute(m, "COLOR_0", c), ao = tiny_attribute(m, "_AO", c);
  for (Eigen::Index v = 0; v < t0.rows(); ++v) {
    const double want = static_cast<double>(v) / static_cast<double>(t0.rows());
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(rgba[static_cast<size_t>(4 * v + k)], want, 0.5 / 65535 + 1e-12);
    EXPECT_EQ(rgba[static_cast<size_t>(4 * v + 3)], 1.0);
    EXPECT_NEAR(ao[static_cast<size_t>(v)], want, 1e-7);
  }
  const Asset back = read_asset(dir.path("ao.glb"));
  EXPECT_EQ(back.signal, AssetSignal::Ao);
  EXPECT_LT((back.transfer - t0).cwiseAbs().maxCoeff(), 1e-7);
}

TEST(Gltf, BadFilesFailWithOneLineNamingTheFileAndTheProblem) {
  const Baked& b = baked();
  const std::string good = gltf_asset_bytes("x.glb", b.mesh, b.transfer, b.metadata, AssetSignal::Transfer, {});
  const std::string text = gltf_asset_bytes("x.gltf", b.mesh, b.transfer, b.metadata, AssetSignal::Transfer, {});
  GltfOptions zipped;
  zipped.compress = true;
  const std::string compressed = gltf_asset_bytes("x.glb", b.mesh, b.transfer, b.metadata, AssetSignal::Transfer, zipped);
  const std::string compressed_text = gltf_asset_bytes("x.gltf", b.mesh, b.transfer, b.metadata, AssetSignal::Transfer, zipped);
  ASSERT_NO_THROW(parse_gltf_asset(good, "x.glb"));
  ASSERT_NO_THROW(parse_gltf_asset(compressed, "x.glb"));
  auto replaced = [](std::string s, const std::string& from, const std::string& to) {
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? s : s.replace(at, from.size(), to);
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {good.substr(0, 15), "truncated GLB header"},
      {good.substr(0, good.size() - 100), "truncated GLB"},
      {"{\"asset\":{\"version\":\"2.0\"", "not valid glTF JSON"},
      {replaced(text, "\"version\":\"2.0\"", "\"version\":\"1.0\""), "not glTF 2.0"},
      {replaced(text, "\"prtsub_asset\":1", "\"other\":1"), "not a prtsub asset"},
      {replaced(text, "\"sh_order\":3", "\"sh_order\":11"), "sh_order"},
      {replaced(text, "\"sh_order\":3", "\"sh_order\":\"3\""), "sh_order"},
      {replaced(text, "data:application/octet-stream;base64,", "x.bin#"), "external file"},
      {replaced(text, "\"count\":" + std::to_string(b.mesh.num_vertices()), "\"count\":5000000000"), "out of range"},
      {replaced(text, "\"count\":" + std::to_string(b.mesh.num_vertices()), "\"count\":" + std::to_string(b.mesh.num_vertices() + 1)), "past the end"},
      {replaced(text, "\"byteOffset\":0", "\"byteOffset\":-4"), "non-negative"},
      {replaced(compressed, "\"mode\":\"TRIANGLES\"", "\"mode\":\"INDICES\"  "), "not one prtsub writes"},
      {replaced(compressed_text, "\"count\":" + std::to_string(3 * b.mesh.num_faces()) + ",\"mode\"", "\"count\":900000000,\"mode\""), "encoded bytes"},
      {replaced(text, "\"componentType\":5126", "\"componentType\":true"), "componentType"},
  };
  for (const auto& [bytes, what] : cases) {
    try {
      parse_gltf_asset(bytes, "bad.glb");
      ADD_FAILURE() << "no error for: " << what;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("bad.glb: ", 0), 0u) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << what << ": " << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
  // An index past the vertices, in a GLB's binary chunk: found by its bytes and overwritten.
  std::string bad = good;
  const Asset a = parse_gltf_asset(good, "x.glb");
  ASSERT_FALSE(a.triangles.empty());
  const uint32_t huge = 1u << 30;
  std::string triangles_bytes;
  for (const Triangle& t : a.triangles)
    for (uint32_t v : t) triangles_bytes.append(reinterpret_cast<const char*>(&v), 4);
  const size_t at = bad.find(triangles_bytes);
  ASSERT_NE(at, std::string::npos);
  std::memcpy(&bad[at], &huge, 4);
  EXPECT_THROW(
      try { parse_gltf_asset(bad, "bad.glb"); } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("refers to vertex 1073741824"), std::string::npos) << e.what();
        throw;
      },
      InputError);
}

TEST(Gltf, NonFiniteValuesAreRefusedAndLeaveNoFile) {
  test::TempDir dir;
  const Baked& b = baked();
  RowMatrixXd t = b.transfer;
  t(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(write_gltf_asset(dir.path("nan.glb"), b.mesh, t, b.metadata, AssetSignal::Transfer), InputError);
  t(1, 2) = 1e300;  // finite, but not as a float
  EXPECT_THROW(write_gltf_asset(dir.path("nan.glb"), b.mesh, t, b.metadata, AssetSignal::Transfer), InputError);
  EXPECT_FALSE(test::file_exists(dir.path("nan.glb")));
  EXPECT_THROW(write_gltf_asset(dir.path("ao.glb"), b.mesh, b.transfer, b.metadata, AssetSignal::Ao), InputError);  // 9 columns
}

TEST(Gltf, PathsEndingInGlbOrGltfInAnyCaseAreGltf) {
  EXPECT_TRUE(is_gltf_path("a/b.glb"));
  EXPECT_TRUE(is_gltf_path("B.GLTF"));
  EXPECT_FALSE(is_gltf_path("a.ply"));
  EXPECT_FALSE(is_gltf_path("a.glb/x"));
  EXPECT_FALSE(is_gltf_path("glb"));
}

}  // namespace
}  // namespace prtsub
