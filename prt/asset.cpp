#include "prtsub/prt/asset.h"

#include "prtsub/prt/output_file.h"

#include <algorithm>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "prtsub/prt/gltf.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

template <class T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));  // x86 and ARM hosts are little-endian; checked in write_asset
  out.append(b, sizeof(T));
}

// t7 for grey transfer; r_t7, g_t7, b_t7 for the channels of RGB transfer.
std::string transfer_property(int channels, Eigen::Index per_channel, Eigen::Index column) {
  if (channels == 1) return "t" + std::to_string(column);
  return std::string(1, "rgb"[column / per_channel]) + "_t" + std::to_string(column % per_channel);
}

bool host_is_little_endian() {
  const uint16_t one = 1;
  unsigned char b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

}  // namespace

AssetSignal parse_asset_signal(const std::string& name) {
  if (name == "transfer") return AssetSignal::Transfer;
  if (name == "ao") return AssetSignal::Ao;
  throw InputError("unknown signal '" + name + "' (transfer, ao)");
}

const char* asset_signal_name(AssetSignal s) { return s == AssetSignal::Ao ? "ao" : "transfer"; }

size_t clamp_ao(RowMatrixXd& t0) {
  const double hi = 1 / kAoPerT0;
  size_t moved = 0;
  for (Eigen::Index i = 0; i < t0.size(); ++i) {
    double& v = t0.data()[i];
    if (v < 0 || v > hi) v = std::clamp(v, 0.0, hi), ++moved;
  }
  return moved;
}

Mesh asset_mesh(const Asset& a) {
  Mesh m;
  m.positions = a.positions;
  m.vertex_position.resize(static_cast<size_t>(a.positions.rows()));
  for (size_t v = 0; v < m.vertex_position.size(); ++v) m.vertex_position[v] = static_cast<uint32_t>(v);
  m.normals = a.normals;
  m.uv = a.uv;
  m.triangles = a.triangles;
  m.source_face = a.source_face;
  m.input_vertices = m.vertex_position.size();
  for (uint32_t s : a.source_face) m.input_triangles = std::max<size_t>(m.input_triangles, size_t(s) + 1);
  return m;
}

namespace {

// The `albedo` line as bake writes it (albedo_description): R,G,B, a grey A, "vertex ..." or
// "map PATH (through the UVs...)".
AlbedoSpec parse_albedo_metadata(const std::string& value, const std::string& path) {
  if (value.rfind("vertex", 0) == 0) return parse_albedo("vertex");
  if (value.rfind("map ", 0) == 0) {
    AlbedoSpec s;
    s.source = AlbedoSource::Map;
    const size_t end = value.rfind(" (through the UVs");
    s.map = value.substr(4, end == std::string::npos ? std::string::npos : end - 4);
    return s;
  }
  try {
    return parse_albedo(value);
  } catch (const InputError& e) {
    throw InputError(path + ": metadata 'albedo " + value + "': " + e.what());
  }
}

}  // namespace

AssetBounces asset_bounces(const Asset& asset, const std::string& path) {
  // bake writes "bounces N (albedo A; ...)", or "N (albedo coloured; ...)" beside an `albedo`
  // line (docs/asset_format.md).
  AssetBounces b;
  for (const auto& [key, value] : asset.metadata) {
    if (key == "albedo") b.spec = parse_albedo_metadata(value, path);
    if (key != "bounces") continue;
    char* end = nullptr;
    const long n = std::strtol(value.c_str(), &end, 10);
    const size_t at = value.find("(albedo ");
    const bool coloured = at != std::string::npos && value.compare(at + 8, 8, "coloured") == 0;
    const double a = at == std::string::npos ? -1 : coloured ? 0 : std::strtod(value.c_str() + at + 8, nullptr);
    if (end == value.c_str() || n < 0 || n > 64 || !(a >= 0 && a <= 1))
      throw InputError(path + ": metadata 'bounces " + value + "' is not 'N (albedo A; ...)' with N in 0..64 and A in [0, 1]");
    b.bounces = static_cast<int>(n), b.albedo = a, b.coloured = coloured;
  }
  if (b.coloured && !b.spec.coloured()) throw InputError(path + ": metadata says the bounces are coloured but has no coloured 'albedo' line");
  if (b.coloured != (asset.channels == 3) && b.bounces > 0)
    throw InputError(path + ": metadata 'bounces' does not match the asset's " + std::to_string(asset.channels) + " transfer channel(s)");
  return b;
}

// An SG asset's values: kept as the file has them, and relit through their SH equivalent.
void set_asset_lobes(Asset& a, const RowMatrixXd& lobes) {
  const SgBasis basis = sg_basis(static_cast<int>(lobes.cols()));
  a.sg = lobes;
  a.order = sg_shading_order(basis);
  a.transfer = sg_to_sh(basis, lobes, a.order);
  a.channels = 1;
}

Asset make_asset(const Mesh& mesh, const RowMatrixXd& transfer, const Metadata& metadata, AssetSignal signal, const RowMatrixX3d& albedo) {
  const int lobes = metadata_lobes(metadata, "(in memory)");
  check_asset_input("(in memory)", mesh, transfer, signal, albedo, lobes);
  Asset a;
  a.positions = vertex_positions(mesh);
  a.normals = mesh.normals;
  a.uv = mesh.uv;
  a.transfer = transfer;
  a.triangles = mesh.triangles;
  a.source_face = mesh.source_face;
  a.metadata = metadata;
  a.signal = signal;
  a.albedo = albedo;
  if (lobes > 0) {
    set_asset_lobes(a, transfer);
    return a;
  }
  a.channels = signal == AssetSignal::Ao ? 1 : transfer_channels(transfer.cols());
  a.order = signal == AssetSignal::Ao ? 1 : static_cast<int>(std::lround(std::sqrt(static_cast<double>(transfer.cols() / a.channels))));
  return a;
}

Metadata sg_convention_metadata(const SgBasis& basis, bool non_negative) {
  char buf[64];
  std::string axes;
  for (const Eigen::Vector3d& mu : basis.axes) {
    std::snprintf(buf, sizeof buf, "%s%.9f,%.9f,%.9f", axes.empty() ? "" : " ", mu.x(), mu.y(), mu.z());
    axes += buf;
  }
  std::snprintf(buf, sizeof buf, "%.17g", basis.sharpness);
  return {
      {"prtsub_asset", "1"},
      {"basis", "spherical-gaussian G_k(w)=exp(sharpness*(mu_k.w-1)) axes=mesh mu_k=spherical-fibonacci z=1-(2k+1)/N phi=k*pi*(3-sqrt(5)) "
                "sharpness=ln2/(1-cos(sqrt(4pi/N)/2))"},
      {"sg_lobes", std::to_string(basis.size())},
      {"sg_sharpness", buf},
      {"sg_axes", axes},
      {"transfer", std::string("V*max(n.w,0)~sum(c_k*G_k(w)) least-squares") + (non_negative ? " c_k>=0" : " signed") +
                       " radiance=albedo/pi*sum(c_k*L_k) L_k=integral(L*G_k)"},
  };
}

int metadata_lobes(const Metadata& metadata, const std::string& path) {
  for (const auto& [key, value] : metadata) {
    if (key != "sg_lobes") continue;
    char* end = nullptr;
    const long n = std::strtol(value.c_str(), &end, 10);
    if (end == value.c_str() || *end != '\0' || n < kMinSgLobes || n > kMaxSgAssetLobes)
      throw InputError(path + ": metadata 'sg_lobes " + value + "' is not a lobe count of " + std::to_string(kMinSgLobes) + " to " +
                       std::to_string(kMaxSgAssetLobes));
    return static_cast<int>(n);
  }
  return 0;
}

const RowMatrixXd& stored_values(const Asset& a) { return a.sg.rows() > 0 ? a.sg : a.transfer; }

Metadata sh_convention_metadata(int order) {
  return {
      {"prtsub_asset", "1"},
      {"sh_basis", "real-orthonormal index=l*(l+1)+m no-condon-shortley y1-1=+c*y y10=+c*z y11=+c*x axes=mesh"},
      {"sh_order", std::to_string(order)},
      {"transfer", "t_i=integral(V*max(n.w,0)*y_i) radiance=albedo/pi*sum(l_i*t_i)"},
  };
}

Metadata ao_metadata() {
  return {
      {"prtsub_asset", "1"},
      {"signal", "ao"},
      {"ao", "ao=(1/pi)*integral(V*max(n.w,0)) in [0,1] (1 unoccluded) radiance=albedo*ambient*ao"},
  };
}

void check_asset_input(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer, AssetSignal signal, const RowMatrixX3d& albedo,
                       int lobes) {
  if (lobes > 0 && (signal != AssetSignal::Transfer || transfer.cols() != lobes))
    throw InputError(path + ": a spherical-Gaussian asset takes " + std::to_string(lobes) + " grey transfer values per vertex, got " +
                     std::to_string(transfer.cols()));
  if (signal == AssetSignal::Ao && transfer.cols() != 1)
    throw InputError(path + ": an AO asset takes one value per vertex, got " + std::to_string(transfer.cols()));
  if (signal == AssetSignal::Transfer && lobes == 0 && transfer_channels(transfer.cols()) == 0)
    throw InputError(path + ": " + std::to_string(transfer.cols()) + " transfer values per vertex is neither N² nor 3·N² for an order N of 1 to 10");
  if (albedo.rows() > 0 && static_cast<size_t>(albedo.rows()) != mesh.num_vertices())
    throw InputError(path + ": " + std::to_string(albedo.rows()) + " albedos for " + std::to_string(mesh.num_vertices()) + " vertices");
  if (albedo.rows() > 0 && !(albedo.allFinite() && albedo.minCoeff() >= 0 && albedo.maxCoeff() <= 1))
    throw InputError(path + ": refusing to write an albedo outside [0, 1]");
  if (!host_is_little_endian()) throw IoError(path + ": big-endian hosts are not supported");
  const size_t V = mesh.num_vertices();
  const Eigen::Index K = transfer.cols();
  if (static_cast<size_t>(transfer.rows()) != V)
    throw InputError(path + ": transfer has " + std::to_string(transfer.rows()) + " rows for " + std::to_string(V) + " vertices");
  const double unit = signal == AssetSignal::Ao ? kAoPerT0 : 1.0;
  if (!transfer.allFinite()) throw InputError(path + ": refusing to write non-finite transfer values");
  if (mesh.has_uv() && static_cast<size_t>(mesh.uv.rows()) != V)
    throw InputError(path + ": the mesh has " + std::to_string(mesh.uv.rows()) + " UVs for " + std::to_string(V) + " vertices");
  if (mesh.has_uv() && !mesh.uv.allFinite()) throw InputError(path + ": refusing to write non-finite UVs");
  for (size_t v = 0; v < V; ++v) {
    for (int c = 0; c < 3; ++c) {
      double p = mesh.positions(mesh.vertex_position[v], c);
      if (!std::isfinite(static_cast<float>(p)))
        throw InputError(path + ": position does not fit in float (vertex " + std::to_string(v) + ")");
    }
    for (Eigen::Index c = 0; c < K; ++c)
      if (!std::isfinite(static_cast<float>(unit * transfer(static_cast<Eigen::Index>(v), c))))
        throw InputError(path + ": transfer value does not fit in float (vertex " + std::to_string(v) + ")");
  }
}

void write_asset(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer_in,
                 const Metadata& metadata, AssetSignal signal, const RowMatrixX3d& albedo) {
  const int lobes = metadata_lobes(metadata, path);
  check_asset_input(path, mesh, transfer_in, signal, albedo, lobes);
  const RowMatrixXd transfer = signal == AssetSignal::Ao ? RowMatrixXd(transfer_in * kAoPerT0) : transfer_in;
  const size_t V = mesh.num_vertices(), F = mesh.num_faces();
  const Eigen::Index K = transfer.cols();
  const bool uv = mesh.has_uv();

  std::string out;
  out.reserve(512 + V * (8 + static_cast<size_t>(K)) * 4 + F * 17);
  out += "ply\nformat binary_little_endian 1.0\n";
  for (const auto& [key, value] : metadata) {
    std::string line = key + " " + value;
    for (char& ch : line)
      if (ch == '\n' || ch == '\r') ch = ' ';
    out += "comment " + line + "\n";
  }
  out += "element vertex " + std::to_string(V) + "\n";
  for (const char* p : {"x", "y", "z", "nx", "ny", "nz"}) out += std::string("property float ") + p + "\n";
  if (uv) out += "property float u\nproperty float v\n";
  if (albedo.rows() > 0) out += "property float albedo_r\nproperty float albedo_g\nproperty float albedo_b\n";
  const int channels = signal == AssetSignal::Ao || lobes > 0 ? 1 : transfer_channels(K);
  if (signal == AssetSignal::Ao) out += "property float ao\n";
  else
    for (Eigen::Index c = 0; c < K; ++c) out += "property float " + transfer_property(channels, K / channels, c) + "\n";
  out += "element face " + std::to_string(F) + "\n";
  out += "property list uchar int vertex_indices\nproperty int source_face\nend_header\n";
  for (size_t v = 0; v < V; ++v) {
    const auto vi = static_cast<Eigen::Index>(v);
    for (int c = 0; c < 3; ++c) put(out, static_cast<float>(mesh.positions(mesh.vertex_position[v], c)));
    for (int c = 0; c < 3; ++c) put(out, static_cast<float>(mesh.normals(vi, c)));
    if (uv)
      for (int c = 0; c < 2; ++c) put(out, static_cast<float>(mesh.uv(vi, c)));
    if (albedo.rows() > 0)
      for (int c = 0; c < 3; ++c) put(out, static_cast<float>(albedo(vi, c)));
    for (Eigen::Index c = 0; c < K; ++c) put(out, static_cast<float>(transfer(vi, c)));
  }
  for (size_t f = 0; f < F; ++f) {
    put<uint8_t>(out, 3);
    for (int k = 0; k < 3; ++k) put<int32_t>(out, static_cast<int32_t>(mesh.triangles[f][k]));
    put<int32_t>(out, static_cast<int32_t>(mesh.source_face[f]));
  }
  write_file_atomically(path, out);
}

namespace {

// The lobes a file names must be the ones sg_basis builds: a consumer relights with its own.
void check_sg_metadata(const Metadata& metadata, const SgBasis& basis, const std::string& path) {
  for (const auto& [key, value] : metadata)
    if (key == "sg_sharpness") {
      if (!sg_sharpness_matches(basis, std::strtod(value.c_str(), nullptr)))
        throw InputError(path + ": metadata 'sg_sharpness " + value + "' is not the sharpness of prtsub's " + std::to_string(basis.size()) +
                         " lobes");
      return;
    }
  throw InputError(path + ": a spherical-Gaussian asset without an 'sg_sharpness' line");
}

}  // namespace

Asset read_asset(const std::string& path) { return parse_asset(read_file_bytes(path), path); }

Asset parse_asset(const std::string& bytes, const std::string& path) {
  const size_t first = bytes.find_first_not_of(" \t\r\n");
  if (bytes.compare(0, 4, "glTF") == 0 || (first != std::string::npos && bytes[first] == '{')) return parse_gltf_asset(bytes, path);
  PlyFile ply = parse_ply(bytes, path);
  const PlyElement* v = ply.element("vertex");
  const PlyElement* f = ply.element("face");
  if (!v || !f) throw InputError(path + ": not a prtsub asset (needs vertex and face elements)");
  if (v->count == 0 || f->count == 0)
    throw InputError(path + ": empty asset (" + std::to_string(v->count) + " vertices, " + std::to_string(f->count) + " faces)");
  Asset a;
  for (const std::string& c : ply.comments) {
    size_t sp = c.find(' ');
    a.metadata.emplace_back(c.substr(0, sp), sp == std::string::npos ? "" : c.substr(sp + 1));
  }
  const Eigen::Index V = static_cast<Eigen::Index>(v->count);
  auto column = [&](const char* name) -> const std::vector<double>& {
    const std::vector<double>* col = v->scalar(name);
    if (!col) throw InputError(path + ": asset vertex element lacks property '" + name + "'");
    return *col;
  };
  a.positions.resize(V, 3);
  a.normals.resize(V, 3);
  const char* names[6] = {"x", "y", "z", "nx", "ny", "nz"};
  for (int c = 0; c < 6; ++c) {
    const auto& col = column(names[c]);
    for (Eigen::Index i = 0; i < V; ++i) (c < 3 ? a.positions(i, c) : a.normals(i, c - 3)) = col[static_cast<size_t>(i)];
  }
  if (v->scalar("u") && v->scalar("v")) {
    a.uv.resize(V, 2);
    for (int c = 0; c < 2; ++c) {
      const auto& col = column(c == 0 ? "u" : "v");
      for (Eigen::Index i = 0; i < V; ++i) a.uv(i, c) = col[static_cast<size_t>(i)];
    }
    if (!a.uv.allFinite()) throw InputError(path + ": a UV holds NaN or Inf");
  }
  if (v->scalar("albedo_r") || v->scalar("albedo_g") || v->scalar("albedo_b")) {
    a.albedo.resize(V, 3);
    for (int c = 0; c < 3; ++c) {
      const auto& col = column(c == 0 ? "albedo_r" : c == 1 ? "albedo_g" : "albedo_b");
      for (Eigen::Index i = 0; i < V; ++i) a.albedo(i, c) = col[static_cast<size_t>(i)];
    }
    if (!(a.albedo.allFinite() && a.albedo.minCoeff() >= 0 && a.albedo.maxCoeff() <= 1))
      throw InputError(path + ": an albedo is outside [0, 1] or not finite");
  }
  int K = 0;
  while (v->scalar("t" + std::to_string(K))) ++K;
  if (K == 0 && v->scalar("r_t0")) {  // RGB transfer: three blocks of N²
    int n = 0;
    while (v->scalar("r_t" + std::to_string(n))) ++n;
    const int order = static_cast<int>(std::lround(std::sqrt(n)));
    if (order * order != n || order > kMaxShOrder)
      throw InputError(path + ": asset has " + std::to_string(n) + " red transfer coefficients; expected N² for an order N of 1 to 10");
    a.channels = 3, a.order = order;
    a.transfer.resize(V, 3 * n);
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < n; ++k) {
        const std::string name = std::string(1, "rgb"[c]) + "_t" + std::to_string(k);
        const auto& col = column(name.c_str());
        for (Eigen::Index i = 0; i < V; ++i) a.transfer(i, c * n + k) = col[static_cast<size_t>(i)];
      }
    K = -1;  // read
  }
  if (K == 0 && v->scalar("ao")) {
    a.signal = AssetSignal::Ao;
    a.order = 1;
    a.transfer.resize(V, 1);
    const auto& col = *v->scalar("ao");
    for (Eigen::Index i = 0; i < V; ++i) a.transfer(i, 0) = col[static_cast<size_t>(i)] / kAoPerT0;
    K = -1;  // read
  }
  const int lobes = metadata_lobes(a.metadata, path);
  if (K >= 0) {
    if (lobes > 0) {  // spherical-Gaussian lobes: c_k in t_k
      if (K != lobes)
        throw InputError(path + ": metadata says " + std::to_string(lobes) + " spherical-Gaussian lobes, but vertices hold " +
                         std::to_string(K) + " transfer values");
      check_sg_metadata(a.metadata, sg_basis(lobes), path);
    } else {
      const int order = static_cast<int>(std::lround(std::sqrt(K)));
      if (K == 0 || order * order != K || order > kMaxShOrder)
        throw InputError(path + ": asset has " + std::to_string(K) + " transfer coefficients; expected N² for an order N of 1 to 10 (or one ao)");
      a.order = order;
    }
    a.transfer.resize(V, K);
    for (int c = 0; c < K; ++c) {
      const auto& col = *v->scalar("t" + std::to_string(c));
      for (Eigen::Index i = 0; i < V; ++i) a.transfer(i, c) = col[static_cast<size_t>(i)];
    }
    if (lobes > 0) set_asset_lobes(a, RowMatrixXd(a.transfer));  // NaN reaches the SH equivalent: the check below names the vertex
  }
  for (Eigen::Index i = 0; i < V; ++i) {
    if (!a.positions.row(i).allFinite() || !a.normals.row(i).allFinite() || !a.transfer.row(i).allFinite())
      throw InputError(path + ": vertex " + std::to_string(i) + " holds NaN or Inf");
  }
  int li = f->list("vertex_indices");
  if (li < 0) throw InputError(path + ": asset face element lacks vertex_indices");
  const auto& offs = f->list_offsets[static_cast<size_t>(li)];
  const auto& vals = f->list_values[static_cast<size_t>(li)];
  const std::vector<double>* src = f->scalar("source_face");
  if (!src) throw InputError(path + ": asset face element lacks source_face");
  a.triangles.resize(f->count);
  a.source_face.resize(f->count);
  for (size_t i = 0; i < f->count; ++i) {
    if (offs[i + 1] - offs[i] != 3) throw InputError(path + ": face " + std::to_string(i) + " is not a triangle");
    const std::string face = path + ": face " + std::to_string(i);
    for (int k = 0; k < 3; ++k) {
      const int64_t idx = index_value(vals[offs[i] + static_cast<size_t>(k)], face + "'s vertex index");
      if (idx < 0 || idx >= static_cast<int64_t>(V))
        throw InputError(face + " refers to vertex " + std::to_string(idx) + " of " + std::to_string(V));
      a.triangles[i][static_cast<size_t>(k)] = static_cast<uint32_t>(idx);
    }
    const int64_t source = index_value((*src)[i], face + "'s source_face");
    if (source < 0 || source > int64_t(UINT32_MAX)) throw InputError(face + " has source_face " + std::to_string(source) + ", out of range");
    a.source_face[i] = static_cast<uint32_t>(source);
  }
  return a;
}

}  // namespace prtsub
