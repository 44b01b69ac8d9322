// glTF 2.0 assets. The writer lays out one buffer: a view per attribute (POSITION, NORMAL,
// TEXCOORD_0, the transfer as _PRT_0.._PRT_k VEC4s or AO as COLOR_0 and _AO), the indices, and
// source_face as an accessor the mesh's extras name (glTF has no per-face attribute). Every
// view starts on a 4-byte boundary and every vertex stride is a multiple of 4, as the spec and
// meshoptimizer's codec both need. With compression each view is encoded on its own
// (ATTRIBUTES or TRIANGLES mode) into the stored buffer, and the views point into a fallback
// buffer that has a length and no data, which is what EXT_meshopt_compression specifies when
// the extension is required. The JSON is nlohmann's, so names and metadata are escaped by it.
//
// The reader accepts what the writer makes, in either container, and nothing is trusted: each
// index is checked against its array, each offset and length against its buffer without
// overflow, and a compressed view may not claim more than 256 times its encoded bytes (the
// codec's own ceiling is 64 for a constant stream), so a file cannot make it allocate without
// bound.
#include "prtsub/prt/gltf.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>

#include "prtsub/prt/base64.h"
#include "prtsub/prt/lights.h"
#include "prtsub/prt/sg_basis.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"
#include "prtsub/version.h"

namespace prtsub {
namespace {

using nlohmann::json;

constexpr int kFloat = 5126, kShort = 5122, kUnsignedShort = 5123, kUnsignedInt = 5125, kUnsignedByte = 5121;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr uint32_t kGlbMagic = 0x46546C67, kJsonChunk = 0x4E4F534A, kBinChunk = 0x004E4942;
constexpr const char* kMeshopt = "EXT_meshopt_compression";
constexpr size_t kMaxDecodeRatio = 256;

template <class T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));  // little-endian hosts only: write_asset's check
  out.append(b, sizeof(T));
}

void pad4(std::string& s, char with) {
  while (s.size() % 4) s.push_back(with);
}

// ---- writing ----

struct View {
  std::string bytes;
  size_t count = 0;   // elements (vertices, indices or faces)
  int stride = 0;     // bytes per element
  int target = 0;     // 0: none
  bool indices = false;
};

struct Writer {
  std::vector<View> views;
  json accessors = json::array();

  int add(View v, int component, const char* type, bool normalized, json min = nullptr, json max = nullptr) {
    const size_t count = v.count;
    views.push_back(std::move(v));
    json a = {{"bufferView", views.size() - 1}, {"componentType", component}, {"count", count}, {"type", type}};
    if (normalized) a["normalized"] = true;
    if (!min.is_null()) a["min"] = std::move(min), a["max"] = std::move(max);
    accessors.push_back(std::move(a));
    return static_cast<int>(accessors.size() - 1);
  }
};

std::string lower_extension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  const size_t slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot);
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

}  // namespace

UpAxis parse_up_axis(const std::string& name) {
  if (name == "y") return UpAxis::Y;
  if (name == "z") return UpAxis::Z;
  throw InputError("unknown up axis '" + name + "' (y, z)");
}

bool is_gltf_path(const std::string& path) {
  const std::string e = lower_extension(path);
  return e == ".glb" || e == ".gltf";
}

Eigen::Matrix3d z_up_to_y_up() {
  Eigen::Matrix3d R;
  R << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return R;
}

std::string gltf_asset_bytes(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer_in,
                             const Metadata& metadata, AssetSignal signal, const GltfOptions& options, const RowMatrixX3d& albedo) {
  const int lobes = metadata_lobes(metadata, path);
  check_asset_input(path, mesh, transfer_in, signal, albedo, lobes);
  const bool ao = signal == AssetSignal::Ao;
  const size_t V = mesh.num_vertices(), F = mesh.num_faces();
  const Eigen::Index K = transfer_in.cols();
  const int channels = ao || lobes > 0 ? 1 : transfer_channels(K);
  const Eigen::Index per_channel = K / channels;
  const int order = ao || lobes > 0 ? 1 : static_cast<int>(std::lround(std::sqrt(static_cast<double>(per_channel))));

  // The file's axes: a Z-up source turns so its +Z is glTF's +Y, the transfer with it.
  const Eigen::Matrix3d R = options.up == UpAxis::Z ? z_up_to_y_up() : Eigen::Matrix3d::Identity();
  RowMatrixX3d positions = vertex_positions(mesh) * R.transpose();
  RowMatrixX3d normals = mesh.normals * R.transpose();
  RowMatrixXd transfer = transfer_in;
  // Lobes keep their coefficients and turn their axes instead (extras.sg_axes).
  if (!ao && lobes == 0 && options.up != UpAxis::Y)
    for (int c = 0; c < channels; ++c)
      transfer.middleCols(c * per_channel, per_channel) = transfer_in.middleCols(c * per_channel, per_channel) * sh_rotation(order, R).transpose();
  for (Eigen::Index v = 0; v < normals.rows(); ++v) {
    const double n = normals.row(v).norm();
    if (n > 0) normals.row(v) /= n;
  }

  Writer w;
  json attributes;
  {
    View pos{{}, V, 12, kArrayBuffer, false}, nrm{{}, V, 12, kArrayBuffer, false};
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (size_t v = 0; v < V; ++v) {
      const auto vi = static_cast<Eigen::Index>(v);
      for (int c = 0; c < 3; ++c) {
        const float p = static_cast<float>(positions(vi, c));
        put(pos.bytes, p);
        put(nrm.bytes, static_cast<float>(normals(vi, c)));
        lo[c] = std::min(lo[c], static_cast<double>(p)), hi[c] = std::max(hi[c], static_cast<double>(p));
      }
    }
    const json min = {lo.x(), lo.y(), lo.z()}, max = {hi.x(), hi.y(), hi.z()};
    attributes["POSITION"] = w.add(std::move(pos), kFloat, "VEC3", false, min, max);
    attributes["NORMAL"] = w.add(std::move(nrm), kFloat, "VEC3", false);
  }
  if (mesh.has_uv()) {
    View uv{{}, V, 8, kArrayBuffer, false};
    for (size_t v = 0; v < V; ++v) {
      put(uv.bytes, static_cast<float>(mesh.uv(static_cast<Eigen::Index>(v), 0)));
      put(uv.bytes, static_cast<float>(1.0 - mesh.uv(static_cast<Eigen::Index>(v), 1)));  // glTF's v runs down
    }
    attributes["TEXCOORD_0"] = w.add(std::move(uv), kFloat, "VEC2", false);
  }
  json quantization = nullptr;
  std::vector<std::string> value_names;
  if (ao) {
    View colour{{}, V, 8, kArrayBuffer, false}, value{{}, V, 4, kArrayBuffer, false};
    for (size_t v = 0; v < V; ++v) {
      const double a = std::clamp(transfer(static_cast<Eigen::Index>(v), 0) * kAoPerT0, 0.0, 1.0);
      const auto q = static_cast<uint16_t>(std::lround(a * 65535));
      for (int c = 0; c < 3; ++c) put(colour.bytes, q);
      put<uint16_t>(colour.bytes, 65535);
      put(value.bytes, static_cast<float>(transfer(static_cast<Eigen::Index>(v), 0) * kAoPerT0));
    }
    attributes["COLOR_0"] = w.add(std::move(colour), kUnsignedShort, "VEC4", true);
    attributes["_AO"] = w.add(std::move(value), kFloat, "SCALAR", false);
    value_names = {"COLOR_0", "_AO"};
  } else {
    std::vector<double> scale(static_cast<size_t>(K), 1.0);
    if (options.quantize) {
      for (Eigen::Index c = 0; c < K; ++c) {
        const double m = transfer.col(c).cwiseAbs().maxCoeff();
        scale[static_cast<size_t>(c)] = m > 0 ? static_cast<double>(static_cast<float>(m)) : 1.0;
      }
      quantization = {{"component_type", "SHORT"}, {"normalized", true}, {"scale", scale},
                      {"decode", "t_i = scale_i * max(q / 32767, -1)"}};
    }
    // Grey: _PRT_k. RGB: _PRT_R_k, _PRT_G_k, _PRT_B_k, each channel zero-padded on its own.
    for (int ch = 0; ch < channels; ++ch) {
      const Eigen::Index first = ch * per_channel, end = first + per_channel;
      for (Eigen::Index k = 0; k * 4 < per_channel; ++k) {
        View view{{}, V, options.quantize ? 8 : 16, kArrayBuffer, false};
        for (size_t v = 0; v < V; ++v)
          for (Eigen::Index c = first + 4 * k; c < first + 4 * k + 4; ++c) {
            const double t = c < end ? transfer(static_cast<Eigen::Index>(v), c) : 0.0;
            if (options.quantize) {
              const double q = std::round(t / scale[static_cast<size_t>(c < end ? c : 0)] * 32767);
              put(view.bytes, static_cast<int16_t>(std::clamp(c < end ? q : 0.0, -32767.0, 32767.0)));
            } else {
              put(view.bytes, static_cast<float>(t));
            }
          }
        const std::string name = std::string("_PRT_") + (channels == 1 ? "" : std::string(1, "RGB"[ch]) + "_") + std::to_string(k);
        attributes[name] = w.add(std::move(view), options.quantize ? kShort : kFloat, "VEC4", options.quantize);
        value_names.push_back(name);
      }
    }
    if (albedo.rows() > 0) {  // glTF's COLOR_0 is linear, as the albedo is
      View colour{{}, V, 12, kArrayBuffer, false};
      for (size_t v = 0; v < V; ++v)
        for (int c = 0; c < 3; ++c) put(colour.bytes, static_cast<float>(albedo(static_cast<Eigen::Index>(v), c)));
      attributes["COLOR_0"] = w.add(std::move(colour), kFloat, "VEC3", false);
    }
  }
  View index{{}, 3 * F, 4, kElementArrayBuffer, true}, source{{}, F, 4, 0, false};
  for (size_t f = 0; f < F; ++f) {
    for (int k = 0; k < 3; ++k) put<uint32_t>(index.bytes, mesh.triangles[f][static_cast<size_t>(k)]);
    put<uint32_t>(source.bytes, mesh.source_face[f]);
  }
  const int indices = w.add(std::move(index), kUnsignedInt, "SCALAR", false);
  const int source_face = w.add(std::move(source), kUnsignedInt, "SCALAR", false);

  // Metadata: the asset's own lines in order, and the facts a consumer needs as fields.
  std::string generator = std::string("prtsub ") + kVersion, source_name;
  json lines = json::array();
  for (const auto& [key, value] : metadata) {
    lines.push_back({key, value});
    if (key == "generator") generator = value;
    if (key == "source") source_name = value;
  }
  json extras = {{"prtsub_asset", 1},
                 {"signal", asset_signal_name(signal)},
                 {"generator", generator},
                 {"source", source_name},
                 {"values", json(value_names)},
                 {"source_face_accessor", source_face},
                 {"up", {{"source_up", options.up == UpAxis::Z ? "z" : "y"},
                         {"rotation", {{R(0, 0), R(0, 1), R(0, 2)}, {R(1, 0), R(1, 1), R(1, 2)}, {R(2, 0), R(2, 1), R(2, 2)}}},
                         {"note", "file = rotation * source, applied to positions, normals and the SH coefficients"}}},
                 {"metadata", lines}};
  if (ao) {
    extras["ao"] = "ao=(1/pi)*integral(V*max(n.w,0)) in [0,1] (1 unoccluded) radiance=albedo*ambient*ao; COLOR_0 = (ao, ao, ao, 1)";
  } else if (lobes > 0) {
    const SgBasis basis = sg_basis(lobes);
    json axes = json::array();
    for (const Eigen::Vector3d& mu : basis.axes) {
      const Eigen::Vector3d turned = R * mu;
      axes.push_back({turned.x(), turned.y(), turned.z()});
    }
    extras["basis"] = "spherical-gaussian";
    extras["sg_lobes"] = lobes;
    extras["sg_sharpness"] = basis.sharpness;
    extras["sg_shading_order"] = sg_shading_order(basis);  // lights projected to SH of this order, then onto the lobes
    extras["sg_axes"] = axes;
    extras["sg_axes_note"] = "the file's axes (glTF: +Y up): prtsub's spherical-Fibonacci axes of the source turned by up.rotation";
    extras["transfer"] = "V*max(n.w,0)~sum(c_k*G_k(w)), G_k(w)=exp(sharpness*(mu_k.w-1)); radiance=albedo/pi*sum(c_k*L_k), L_k=integral(L*G_k)";
    extras["transfer_layout"] = "_PRT_k holds c_{4k}..c_{4k+3}; the last is zero-padded";
    if (!quantization.is_null()) extras["quantization"] = quantization;
  } else {
    extras["sh_order"] = order;
    extras["sh_coefficients"] = per_channel;
    extras["channels"] = channels;
    extras["sh_basis"] = "real-orthonormal index=l*(l+1)+m no-condon-shortley y1-1=+c*y y10=+c*z y11=+c*x";
    extras["sh_axes"] = "the file's (glTF: +Y up, right-handed)";
    extras["transfer"] = "t_i=integral(V*max(n.w,0)*y_i); excludes albedo/pi: radiance=albedo/pi*sum(l_i*t_i)";
    extras["transfer_layout"] = channels == 1 ? "_PRT_k holds t_{4k}..t_{4k+3}; the last is zero-padded"
                                              : "_PRT_R_k, _PRT_G_k, _PRT_B_k hold channel c's t_{4k}..t_{4k+3}; each channel's last is zero-padded";
    if (channels == 3) extras["channel_rule"] = "radiance_c=albedo_c/pi*sum(l_c,i*t_c,i): each channel's transfer bounced by that channel's albedo";
    if (albedo.rows() > 0) extras["albedo"] = "COLOR_0: the surface's own linear albedo at the vertex (not folded into t)";
    if (!quantization.is_null()) extras["quantization"] = quantization;
  }

  // One buffer: the views in order, each 4-aligned; with compression, each view encoded.
  std::string stored;
  json views = json::array();
  size_t fallback_size = 0;
  for (const View& v : w.views) {
    json view;
    if (!options.compress) {
      view = {{"buffer", 0}, {"byteOffset", stored.size()}, {"byteLength", v.bytes.size()}};
      stored += v.bytes;
      pad4(stored, '\0');
    } else {
      std::vector<unsigned char> enc;
      size_t n = 0;
      if (v.indices) {
        enc.resize(meshopt_encodeIndexBufferBound(v.count, V));
        std::vector<uint32_t> idx(v.count);
        std::memcpy(idx.data(), v.bytes.data(), v.bytes.size());
        meshopt_encodeIndexVersion(1);  // the extension's TRIANGLES mode is version 1 (header 0xE1)
        n = meshopt_encodeIndexBuffer(enc.data(), enc.size(), idx.data(), v.count);
      } else {
        enc.resize(meshopt_encodeVertexBufferBound(v.count, static_cast<size_t>(v.stride)));
        n = meshopt_encodeVertexBuffer(enc.data(), enc.size(), v.bytes.data(), v.count, static_cast<size_t>(v.stride));
      }
      if (n == 0) throw InputError(path + ": meshoptimizer could not encode a buffer view");
      view = {{"buffer", 1}, {"byteOffset", fallback_size}, {"byteLength", v.bytes.size()}};
      view["extensions"][kMeshopt] = {{"buffer", 0}, {"byteOffset", stored.size()}, {"byteLength", n},
                                      {"byteStride", v.stride}, {"count", v.count},
                                      {"mode", v.indices ? "TRIANGLES" : "ATTRIBUTES"}};
      stored.append(reinterpret_cast<const char*>(enc.data()), n);
      pad4(stored, '\0');
      fallback_size += v.bytes.size();
      fallback_size += (4 - fallback_size % 4) % 4;
    }
    if (v.target == kArrayBuffer) view["byteStride"] = v.stride;
    if (v.target) view["target"] = v.target;
    views.push_back(std::move(view));
  }

  const bool glb = lower_extension(path) == ".glb";
  json buffers = json::array();
  json buffer = {{"byteLength", stored.size()}};
  if (!glb) buffer["uri"] = "data:application/octet-stream;base64," + base64_encode(stored);
  buffers.push_back(buffer);
  if (options.compress) buffers.push_back({{"byteLength", fallback_size}, {"extensions", {{kMeshopt, {{"fallback", true}}}}}});

  json doc = {{"asset", {{"version", "2.0"}, {"generator", generator}}},
              {"scene", 0},
              {"scenes", json::array({json{{"nodes", json::array({0})}}})},
              {"nodes", json::array({json{{"mesh", 0}, {"name", "prtsub asset"}}})},
              {"meshes", json::array({json{{"name", "prtsub asset"},
                                           {"primitives", json::array({json{{"attributes", attributes}, {"indices", indices}, {"mode", 4}}})},
                                           {"extras", extras}}})},
              {"accessors", w.accessors},
              {"bufferViews", views},
              {"buffers", buffers}};
  if (options.compress) doc["extensionsUsed"] = json::array({kMeshopt}), doc["extensionsRequired"] = json::array({kMeshopt});

  std::string text = doc.dump(-1, ' ', false, json::error_handler_t::replace);
  if (!glb) return text + "\n";
  pad4(text, ' ');
  std::string out;
  out.reserve(28 + text.size() + stored.size());
  put<uint32_t>(out, kGlbMagic);
  put<uint32_t>(out, 2);
  put<uint32_t>(out, static_cast<uint32_t>(28 + text.size() + stored.size()));
  put<uint32_t>(out, static_cast<uint32_t>(text.size()));
  put<uint32_t>(out, kJsonChunk);
  out += text;
  put<uint32_t>(out, static_cast<uint32_t>(stored.size()));
  put<uint32_t>(out, kBinChunk);
  out += stored;
  if (out.size() > UINT32_MAX) throw InputError(path + ": the asset is over 4 GiB, more than a GLB holds");
  return out;
}

void write_gltf_asset(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer,
                      const Metadata& metadata, AssetSignal signal, const GltfOptions& options, const RowMatrixX3d& albedo) {
  write_file_atomically(path, gltf_asset_bytes(path, mesh, transfer, metadata, signal, options, albedo));
}

// ---- reading ----

namespace {

struct Reader {
  const std::string& path;
  json doc;
  std::vector<std::string> buffers;       // each buffer's bytes (empty for a fallback)
  std::vector<bool> fallback;
  std::vector<std::string> decoded;        // per view: decompressed bytes, once
  std::vector<bool> is_decoded;

  [[noreturn]] void fail(const std::string& what) const { throw InputError(path + ": " + what); }

  const json& member(const json& obj, const char* key, const std::string& where) const {
    if (!obj.is_object() || !obj.contains(key)) fail(where + " lacks '" + key + "'");
    return obj[key];
  }
  size_t count_of(const json& obj, const char* key, const std::string& where, size_t limit) const {
    const json& v = member(obj, key, where);
    if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0)) fail(where + "'s '" + key + "' is not a non-negative integer");
    const uint64_t n = v.get<uint64_t>();
    if (n > limit) fail(where + "'s '" + key + "' is " + std::to_string(n) + ", out of range (at most " + std::to_string(limit) + ")");
    return static_cast<size_t>(n);
  }
  size_t optional_count(const json& obj, const char* key, const std::string& where, size_t limit, size_t fallback_value) const {
    return obj.is_object() && obj.contains(key) ? count_of(obj, key, where, limit) : fallback_value;
  }
  const json& element(const char* array, size_t i) const {
    const json& a = member(doc, array, "the file");
    if (!a.is_array() || i >= a.size()) fail(std::string("no ") + array + "[" + std::to_string(i) + "]");
    return a[i];
  }

  void load_buffers(const std::string* bin) {
    const json& list = member(doc, "buffers", "the file");
    if (!list.is_array()) fail("'buffers' is not an array");
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string where = "buffers[" + std::to_string(i) + "]";
      const json& b = list[i];
      const size_t length = count_of(b, "byteLength", where, UINT32_MAX);
      std::string bytes;
      bool is_fallback = b.contains("extensions") && b["extensions"].is_object() && b["extensions"].contains(kMeshopt) &&
                         b["extensions"][kMeshopt].is_object() && b["extensions"][kMeshopt].value("fallback", false);
      if (b.contains("uri")) {
        if (!b["uri"].is_string()) fail(where + "'s uri is not a string");
        const std::string& uri = b["uri"].get_ref<const std::string&>();
        const size_t comma = uri.find(',');
        if (uri.rfind("data:", 0) != 0 || comma == std::string::npos || uri.substr(0, comma).find(";base64") == std::string::npos)
          fail(where + " refers to an external file; prtsub reads self-contained assets (.glb, or .gltf with data: URIs)");
        if (!base64_decode(uri, comma + 1, bytes)) fail(where + "'s data: URI is not valid base64");
      } else if (i == 0 && bin) {
        bytes = *bin;
      } else if (!is_fallback) {
        fail(where + " has no data (no uri, and not the GLB's binary chunk)");
      }
      if (!is_fallback && bytes.size() < length)
        fail(where + " declares " + std::to_string(length) + " bytes but holds " + std::to_string(bytes.size()));
      if (!is_fallback) bytes.resize(length);
      buffers.push_back(std::move(bytes));
      fallback.push_back(is_fallback);
    }
    const size_t views = doc.contains("bufferViews") && doc["bufferViews"].is_array() ? doc["bufferViews"].size() : 0;
    decoded.assign(views, {});
    is_decoded.assign(views, false);
  }

  // The bytes of buffer `b` from `offset`, `length` long, checked.
  std::string slice(size_t b, size_t offset, size_t length, const std::string& where) const {
    if (b >= buffers.size()) fail(where + " names buffer " + std::to_string(b) + " of " + std::to_string(buffers.size()));
    if (fallback[b]) fail(where + " reads the fallback buffer, which holds no data");
    const std::string& data = buffers[b];
    if (offset > data.size() || length > data.size() - offset)
      fail(where + " runs past the end of buffer " + std::to_string(b) + " (" + std::to_string(offset) + " + " + std::to_string(length) +
           " > " + std::to_string(data.size()) + ")");
    return data.substr(offset, length);
  }

  const std::string& view_bytes(size_t index, size_t& stride) {
    const std::string where = "bufferViews[" + std::to_string(index) + "]";
    const json& v = element("bufferViews", index);
    stride = optional_count(v, "byteStride", where, 252, 0);
    if (index >= decoded.size()) fail(where + " is out of range");
    if (is_decoded[index]) return decoded[index];
    const size_t length = count_of(v, "byteLength", where, UINT32_MAX);
    if (v.contains("extensions") && v["extensions"].is_object() && v["extensions"].contains(kMeshopt)) {
      const json& e = v["extensions"][kMeshopt];
      const std::string ew = where + "'s " + kMeshopt;
      const size_t b = count_of(e, "buffer", ew, UINT32_MAX);
      const std::string enc = slice(b, optional_count(e, "byteOffset", ew, UINT32_MAX, 0), count_of(e, "byteLength", ew, UINT32_MAX), ew);
      const size_t esize = count_of(e, "byteStride", ew, 256), count = count_of(e, "count", ew, UINT32_MAX);
      if (esize == 0 || esize % 4) fail(ew + "'s byteStride " + std::to_string(esize) + " is not a positive multiple of 4");
      const json& mode = member(e, "mode", ew);
      if (!mode.is_string()) fail(ew + "'s mode is not a string");
      if (count > (enc.size() + 1024) * kMaxDecodeRatio / esize)
        fail(ew + " claims " + std::to_string(count) + " elements from " + std::to_string(enc.size()) + " encoded bytes");
      if (count * esize > length) fail(ew + " decodes to more than the view's " + std::to_string(length) + " bytes");
      std::string out(count * esize, '\0');
      const auto* src = reinterpret_cast<const unsigned char*>(enc.data());
      int rc = -1;
      if (mode == "ATTRIBUTES") {
        rc = meshopt_decodeVertexBuffer(out.data(), count, esize, src, enc.size());
      } else if (mode == "TRIANGLES") {
        if (count % 3 || (esize != 2 && esize != 4)) fail(ew + ": TRIANGLES needs a count divisible by 3 and a stride of 2 or 4");
        rc = meshopt_decodeIndexBuffer(out.data(), count, esize, src, enc.size());
      } else {
        fail(ew + "'s mode '" + mode.get<std::string>() + "' is not one prtsub writes (ATTRIBUTES, TRIANGLES)");
      }
      if (rc != 0) fail(ew + ": the compressed data does not decode (meshoptimizer error " + std::to_string(rc) + ")");
      if (e.contains("filter") && e["filter"] != "NONE") fail(ew + " uses a filter, which prtsub does not write");
      if (stride == 0 && mode == "ATTRIBUTES") stride = esize;
      decoded[index] = std::move(out);
    } else {
      decoded[index] = slice(count_of(v, "buffer", where, UINT32_MAX), optional_count(v, "byteOffset", where, UINT32_MAX, 0), length, where);
    }
    is_decoded[index] = true;
    return decoded[index];
  }

  // Accessor `index` as count × components doubles, normalized integers mapped to [-1, 1] or
  // [0, 1] as the spec says.
  std::vector<double> accessor(size_t index, const char* type, int components, std::vector<int> allowed, size_t& count) {
    const std::string where = "accessors[" + std::to_string(index) + "]";
    const json& a = element("accessors", index);
    if (!a.contains("type") || a["type"] != type) fail(where + " is not a " + type);
    const json& ct = member(a, "componentType", where);
    const int component = ct.is_number_integer() ? ct.get<int>() : 0;
    if (std::find(allowed.begin(), allowed.end(), component) == allowed.end())
      fail(where + " has componentType " + ct.dump() + ", not one this attribute takes");
    const bool normalized = a.value("normalized", false);
    if (a.contains("sparse")) fail(where + " is sparse, which prtsub does not write");
    count = count_of(a, "count", where, UINT32_MAX);
    const size_t size = component == kFloat || component == kUnsignedInt ? 4 : component == kUnsignedByte ? 1 : 2;
    const size_t element_size = size * static_cast<size_t>(components);
    size_t stride = 0;
    const std::string& bytes = view_bytes(count_of(a, "bufferView", where, UINT32_MAX), stride);
    if (stride == 0) stride = element_size;
    if (stride < element_size) fail(where + "'s stride " + std::to_string(stride) + " is less than its element");
    const size_t offset = optional_count(a, "byteOffset", where, UINT32_MAX, 0);
    if (count > 0 && (offset > bytes.size() || (count - 1) > (bytes.size() - offset) / stride ||
                      element_size > bytes.size() - offset - (count - 1) * stride))
      fail(where + " runs past the end of its buffer view");
    std::vector<double> out(count * static_cast<size_t>(components));
    for (size_t i = 0; i < count; ++i)
      for (int c = 0; c < components; ++c) {
        const char* p = bytes.data() + offset + i * stride + static_cast<size_t>(c) * size;
        double x = 0;
        if (component == kFloat) {
          float f;
          std::memcpy(&f, p, 4);
          x = f;
        } else if (component == kUnsignedInt) {
          uint32_t u;
          std::memcpy(&u, p, 4);
          x = u;
        } else if (component == kShort) {
          int16_t s;
          std::memcpy(&s, p, 2);
          x = normalized ? std::max(s / 32767.0, -1.0) : s;
        } else if (component == kUnsignedShort) {
          uint16_t u;
          std::memcpy(&u, p, 2);
          x = normalized ? u / 65535.0 : u;
        } else {
          x = normalized ? static_cast<unsigned char>(*p) / 255.0 : static_cast<unsigned char>(*p);
        }
        out[i * static_cast<size_t>(components) + static_cast<size_t>(c)] = x;
      }
    return out;
  }
};

}  // namespace

namespace {

Asset parse_gltf(const std::string& bytes, const std::string& path) {
  Reader r{path, {}, {}, {}, {}, {}};
  std::string text, bin;
  bool has_bin = false;
  if (bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0) {
    auto word = [&](size_t at) {
      uint32_t u;
      std::memcpy(&u, bytes.data() + at, 4);
      return u;
    };
    if (bytes.size() < 20) r.fail("truncated GLB header");
    if (word(4) != 2) r.fail("GLB version " + std::to_string(word(4)) + ", not 2");
    const size_t total = word(8);
    if (total > bytes.size()) r.fail("truncated GLB (" + std::to_string(bytes.size()) + " of " + std::to_string(total) + " bytes)");
    size_t at = 12;
    bool first = true;
    while (at + 8 <= total) {
      const size_t length = word(at);
      const uint32_t type = word(at + 4);
      at += 8;
      if (length > total - at) r.fail("a GLB chunk runs past the end of the file");
      if (first && type != kJsonChunk) r.fail("the GLB's first chunk is not JSON");
      if (first) text = bytes.substr(at, length);
      else if (type == kBinChunk && !has_bin) bin = bytes.substr(at, length), has_bin = true;
      first = false;
      at += length;
    }
    if (first) r.fail("the GLB has no JSON chunk");
  } else {
    text = bytes;
  }
  try {
    r.doc = json::parse(text);
  } catch (const json::exception& e) {
    r.fail(std::string("not valid glTF JSON: ") + e.what());
  }
  if (!r.doc.is_object()) r.fail("not a glTF document (its JSON is not an object)");
  const json& asset_info = r.member(r.doc, "asset", "the file");
  if (!asset_info.is_object() || !asset_info.contains("version") || asset_info["version"] != "2.0") r.fail("not glTF 2.0 (asset.version)");
  if (r.doc.contains("extensionsRequired") && r.doc["extensionsRequired"].is_array())
    for (const json& e : r.doc["extensionsRequired"])
      if (e != kMeshopt) r.fail("requires extension " + e.dump() + ", which prtsub does not read");
  r.load_buffers(has_bin ? &bin : nullptr);

  const json& mesh = r.element("meshes", 0);
  const json& extras = r.member(mesh, "extras", "meshes[0]");
  if (!extras.is_object() || !extras.contains("prtsub_asset")) r.fail("not a prtsub asset (meshes[0].extras has no prtsub_asset)");
  const json& prims = r.member(mesh, "primitives", "meshes[0]");
  if (!prims.is_array() || prims.empty()) r.fail("meshes[0] has no primitives");
  const json& prim = prims[0];
  if (prim.contains("mode") && prim["mode"] != 4) r.fail("meshes[0].primitives[0] is not a triangle list (mode 4)");
  const json& attr = r.member(prim, "attributes", "meshes[0].primitives[0]");
  auto attribute = [&](const char* name) -> size_t {
    if (!attr.is_object() || !attr.contains(name)) r.fail(std::string("the primitive lacks attribute ") + name);
    return r.count_of(attr, name, std::string("attribute ") + name, UINT32_MAX);
  };

  Asset a;
  int lobes = 0;  // a spherical-Gaussian asset's lobe count
  size_t V = 0, n = 0;
  const std::vector<double> pos = r.accessor(attribute("POSITION"), "VEC3", 3, {kFloat}, V);
  const std::vector<double> nrm = r.accessor(attribute("NORMAL"), "VEC3", 3, {kFloat}, n);
  if (V == 0) r.fail("empty asset (0 vertices)");
  if (n != V) r.fail("NORMAL has " + std::to_string(n) + " values for " + std::to_string(V) + " vertices");
  const auto Vi = static_cast<Eigen::Index>(V);
  a.positions = Eigen::Map<const RowMatrixX3d>(pos.data(), Vi, 3);
  a.normals = Eigen::Map<const RowMatrixX3d>(nrm.data(), Vi, 3);
  if (attr.contains("TEXCOORD_0")) {
    const std::vector<double> uv = r.accessor(attribute("TEXCOORD_0"), "VEC2", 2, {kFloat}, n);
    if (n != V) r.fail("TEXCOORD_0 has " + std::to_string(n) + " values for " + std::to_string(V) + " vertices");
    a.uv = Eigen::Map<const RowMatrixX2d>(uv.data(), Vi, 2);
    a.uv.col(1) = (1.0 - a.uv.col(1).array()).matrix();  // back to the input's v
    if (!a.uv.allFinite()) r.fail("a UV holds NaN or Inf");
  }
  const std::string signal = extras.value("signal", std::string("transfer"));
  if (signal == "ao") {
    a.signal = AssetSignal::Ao;
    a.order = 1;
    const std::vector<double> ao = r.accessor(attribute("_AO"), "SCALAR", 1, {kFloat}, n);
    if (n != V) r.fail("_AO has " + std::to_string(n) + " values for " + std::to_string(V) + " vertices");
    a.transfer.resize(Vi, 1);
    for (Eigen::Index i = 0; i < Vi; ++i) a.transfer(i, 0) = ao[static_cast<size_t>(i)] / kAoPerT0;
  } else if (signal == "transfer") {
    int per_channel = 0;
    if (extras.contains("sg_lobes")) {  // lobes: read as one channel of N values, made an SG asset below
      const json& n_lobes = extras["sg_lobes"];
      lobes = n_lobes.is_number_integer() ? n_lobes.get<int>() : 0;
      if (lobes < kMinSgLobes || lobes > kMaxSgAssetLobes)
        r.fail("extras.sg_lobes " + n_lobes.dump() + " is not a lobe count of " + std::to_string(kMinSgLobes) + " to " +
               std::to_string(kMaxSgAssetLobes));
      const json& sharp = extras.value("sg_sharpness", json());
      if (!sharp.is_number() || !sg_sharpness_matches(sg_basis(lobes), sharp.get<double>()))
        r.fail("extras.sg_sharpness " + sharp.dump() + " is not the sharpness of prtsub's " + std::to_string(lobes) + " lobes");
      per_channel = lobes;
    } else {
      const json& o = r.member(extras, "sh_order", "meshes[0].extras");
      const int order = o.is_number_integer() ? o.get<int>() : 0;
      if (order < 1 || order > kMaxShOrder) r.fail("extras.sh_order " + o.dump() + " is not an order of 1 to 10");
      per_channel = order * order;
      a.order = order;
    }
    const json ch = extras.value("channels", json(1));
    const int channels = ch.is_number_integer() ? ch.get<int>() : 0;
    if (channels != 1 && channels != 3) r.fail("extras.channels " + ch.dump() + " is neither 1 nor 3");
    if (lobes > 0 && channels != 1) r.fail("extras.channels: spherical-Gaussian transfer is grey (one channel)");
    const int K = channels * per_channel;
    std::vector<double> scale(static_cast<size_t>(K), 1.0);
    if (extras.contains("quantization")) {
      const json& s = r.member(extras["quantization"], "scale", "extras.quantization");
      if (!s.is_array() || s.size() != static_cast<size_t>(K)) r.fail("extras.quantization.scale does not hold one scale per coefficient");
      for (int c = 0; c < K; ++c) {
        if (!s[static_cast<size_t>(c)].is_number()) r.fail("extras.quantization.scale holds a non-number");
        scale[static_cast<size_t>(c)] = s[static_cast<size_t>(c)].get<double>();
      }
    }
    a.channels = channels;
    a.transfer.resize(Vi, K);
    for (int chn = 0; chn < channels; ++chn)
      for (int k = 0; 4 * k < per_channel; ++k) {
        const std::string name = std::string("_PRT_") + (channels == 1 ? "" : std::string(1, "RGB"[chn]) + "_") + std::to_string(k);
        const std::vector<double> t = r.accessor(attribute(name.c_str()), "VEC4", 4, {kFloat, kShort}, n);
        if (n != V) r.fail(name + " has " + std::to_string(n) + " values for " + std::to_string(V) + " vertices");
        const int first = chn * per_channel;
        for (Eigen::Index i = 0; i < Vi; ++i)
          for (int c = first + 4 * k; c < std::min(first + per_channel, first + 4 * k + 4); ++c)
            a.transfer(i, c) = scale[static_cast<size_t>(c)] * t[static_cast<size_t>(i) * 4 + static_cast<size_t>(c - first - 4 * k)];
      }
    if (attr.contains("COLOR_0")) {
      const std::vector<double> rgb = r.accessor(attribute("COLOR_0"), "VEC3", 3, {kFloat}, n);
      if (n != V) r.fail("COLOR_0 has " + std::to_string(n) + " values for " + std::to_string(V) + " vertices");
      a.albedo = Eigen::Map<const RowMatrixX3d>(rgb.data(), Vi, 3);
      if (!(a.albedo.allFinite() && a.albedo.minCoeff() >= 0 && a.albedo.maxCoeff() <= 1)) r.fail("COLOR_0 holds an albedo outside [0, 1]");
    }
  } else {
    r.fail("extras.signal '" + signal + "' is neither transfer nor ao");
  }
  for (Eigen::Index i = 0; i < Vi; ++i)
    if (!a.positions.row(i).allFinite() || !a.normals.row(i).allFinite() || !a.transfer.row(i).allFinite())
      r.fail("vertex " + std::to_string(i) + " holds NaN or Inf");

  size_t I = 0, F = 0;
  const std::vector<double> idx = r.accessor(r.count_of(prim, "indices", "meshes[0].primitives[0]", UINT32_MAX), "SCALAR", 1,
                                             {kUnsignedInt, kUnsignedShort, kUnsignedByte}, I);
  if (I == 0 || I % 3) r.fail(std::to_string(I) + " indices is not a positive multiple of 3");
  const std::vector<double> src = r.accessor(r.count_of(extras, "source_face_accessor", "meshes[0].extras", UINT32_MAX), "SCALAR", 1, {kUnsignedInt}, F);
  if (F * 3 != I) r.fail("source_face has " + std::to_string(F) + " values for " + std::to_string(I / 3) + " faces");
  a.triangles.resize(F);
  a.source_face.resize(F);
  for (size_t f = 0; f < F; ++f) {
    for (size_t k = 0; k < 3; ++k) {
      const double v = idx[3 * f + k];
      if (v >= static_cast<double>(V)) r.fail("face " + std::to_string(f) + " refers to vertex " + std::to_string(static_cast<uint64_t>(v)) + " of " + std::to_string(V));
      a.triangles[f][k] = static_cast<uint32_t>(v);
    }
    a.source_face[f] = static_cast<uint32_t>(src[f]);
  }

  if (extras.contains("metadata") && extras["metadata"].is_array())
    for (const json& line : extras["metadata"])
      if (line.is_array() && line.size() == 2 && line[0].is_string() && line[1].is_string())
        a.metadata.emplace_back(line[0].get<std::string>(), line[1].get<std::string>());

  // Back to the source's axes, so every command sees the asset as the PLY of the same bake.
  if (extras.contains("up")) {
    const json& rot = r.member(extras["up"], "rotation", "extras.up");
    Eigen::Matrix3d R;
    if (!rot.is_array() || rot.size() != 3) r.fail("extras.up.rotation is not a 3 by 3 matrix");
    for (size_t i = 0; i < 3; ++i) {
      if (!rot[i].is_array() || rot[i].size() != 3) r.fail("extras.up.rotation is not a 3 by 3 matrix");
      for (size_t j = 0; j < 3; ++j) {
        if (!rot[i][j].is_number()) r.fail("extras.up.rotation holds a non-number");
        R(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = rot[i][j].get<double>();
      }
    }
    if (!R.allFinite() || (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 || R.determinant() < 0)
      r.fail("extras.up.rotation is not a rotation");
    if (!R.isIdentity(1e-12)) {
      a.positions = a.positions * R;  // rows: p_source = Rᵀ p_file
      a.normals = a.normals * R;
      if (a.signal == AssetSignal::Transfer && lobes == 0) {
        const Eigen::Index k = a.transfer.cols() / a.channels;
        for (int c = 0; c < a.channels; ++c)
          a.transfer.middleCols(c * k, k) = (a.transfer.middleCols(c * k, k) * sh_rotation(a.order, R.transpose()).transpose()).eval();
      }
    }
  }
  if (lobes > 0) set_asset_lobes(a, RowMatrixXd(a.transfer));  // the coefficients of the source's own axes
  return a;
}

}  // namespace

Asset parse_gltf_asset(const std::string& bytes, const std::string& path) {
  try {
    return parse_gltf(bytes, path);
  } catch (const nlohmann::json::exception& e) {  // a member of the wrong JSON type
    throw InputError(path + ": malformed glTF (" + e.what() + ")");
  }
}

}  // namespace prtsub
