// Uniform 1→4 refinement with OpenSubdiv Far. Far's bilinear scheme would turn triangles into
// quads, so the topology is Loop's and positions are interpolated with InterpolateVarying
// (exact edge midpoints: the linear split) or Interpolate (Loop's smooth positions). Render
// vertices are a face-varying channel with linear interpolation everywhere, so a crease's two
// sides refine separately. For Loop, edges on creases are tagged infinitely sharp, so hard
// edges stay hard.
#include "prtsub/subdiv/uniform.h"

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <memory>
#include <numeric>

#include "prtsub/subdiv/adjacency.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/mesh_io.h"

namespace prtsub {
namespace {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

struct Vec2 {
  double u = 0, v = 0;
  void Clear(void* = nullptr) { u = v = 0; }
  void AddWithWeight(const Vec2& s, float w) { u += w * s.u, v += w * s.v; }
};

struct Vec3 {
  double x = 0, y = 0, z = 0;
  void Clear(void* = nullptr) { x = y = z = 0; }
  void AddWithWeight(const Vec3& s, float w) { x += w * s.x, y += w * s.y, z += w * s.z; }
};

void far_error(Far::ErrorType, const char* message) { throw InputError(std::string("OpenSubdiv: ") + message); }

}  // namespace

UniformScheme parse_uniform_scheme(const std::string& name) {
  if (name == "linear") return UniformScheme::Linear;
  if (name == "loop") return UniformScheme::Loop;
  throw InputError("unknown uniform scheme '" + name + "' (linear, loop)");
}

const char* uniform_scheme_name(UniformScheme s) { return s == UniformScheme::Loop ? "loop" : "linear"; }

namespace {

// Crease edges (faces on either side use different render vertices) are infinitely sharp for
// Loop, as (lower, higher) position pairs.
void crease_tags(const Mesh& mesh, std::vector<int>& pairs, std::vector<float>& weights) {
  const EdgeAdjacency adj = edge_adjacency(mesh.triangles, &mesh.vertex_position);
  // The render vertices at the lower and the higher position of half-edge h.
  auto render_pair = [&](uint32_t h) {
    const uint32_t a = half_edge_tail(mesh.triangles, h), b = half_edge_head(mesh.triangles, h);
    return mesh.vertex_position[a] < mesh.vertex_position[b] ? std::make_pair(a, b) : std::make_pair(b, a);
  };
  for (size_t e = 0; e < adj.num_edges(); ++e) {
    if (adj.valence(e) < 2) continue;
    const uint32_t* h = adj.edge_begin(e);
    if (render_pair(h[0]) == render_pair(h[1])) continue;
    const uint32_t a = mesh.vertex_position[half_edge_tail(mesh.triangles, h[0])];
    const uint32_t b = mesh.vertex_position[half_edge_head(mesh.triangles, h[0])];
    pairs.push_back(static_cast<int>(std::min(a, b))), pairs.push_back(static_cast<int>(std::max(a, b)));
    weights.push_back(Sdc::Crease::SHARPNESS_INFINITE);
  }
}

// Far's topology over positions, with render vertices as one face-varying channel, refined.
std::unique_ptr<Far::TopologyRefiner> refine_topology(const Mesh& mesh, const UniformOptions& opt) {
  const int F = static_cast<int>(mesh.num_faces());
  std::vector<int> verts_per_face(static_cast<size_t>(F), 3), pos_idx, fvar_idx;
  for (const Triangle& t : mesh.triangles)
    for (uint32_t v : t) pos_idx.push_back(static_cast<int>(mesh.vertex_position[v])), fvar_idx.push_back(static_cast<int>(v));
  std::vector<int> crease_pairs;
  std::vector<float> crease_weights;
  if (opt.scheme == UniformScheme::Loop) crease_tags(mesh, crease_pairs, crease_weights);
  Far::TopologyDescriptor desc;
  desc.numVertices = static_cast<int>(mesh.positions.rows());
  desc.numFaces = F;
  desc.numVertsPerFace = verts_per_face.data();
  desc.vertIndicesPerFace = pos_idx.data();
  desc.numCreases = static_cast<int>(crease_weights.size());
  desc.creaseVertexIndexPairs = crease_pairs.data();
  desc.creaseWeights = crease_weights.data();
  Far::TopologyDescriptor::FVarChannel channel;
  channel.numValues = static_cast<int>(mesh.num_vertices());
  channel.valueIndices = fvar_idx.data();
  desc.numFVarChannels = 1;
  desc.fvarChannels = &channel;
  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
  sdc.SetFVarLinearInterpolation(Sdc::Options::FVAR_LINEAR_ALL);
  Far::SetErrorCallback(far_error);
  std::unique_ptr<Far::TopologyRefiner> refiner(Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Create(
      desc, Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Options(Sdc::SCHEME_LOOP, sdc)));
  if (!refiner) throw InputError("OpenSubdiv could not build the topology");
  refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(opt.levels));
  return refiner;
}

// Positions (vertex data), normals and UVs (face-varying) at every level; the last level's
// values start at `p`, `n` and `uv`.
struct Primvars {
  std::vector<Vec3> pos, nrm, rgb;
  std::vector<Vec2> uvs;
  const Vec3 *p = nullptr, *n = nullptr, *c = nullptr;
  const Vec2* uv = nullptr;
};

Primvars interpolate(const Far::TopologyRefiner& refiner, const Mesh& mesh, const UniformOptions& opt) {
  Primvars pv;
  pv.pos.resize(static_cast<size_t>(refiner.GetNumVerticesTotal()));
  pv.nrm.resize(static_cast<size_t>(refiner.GetNumFVarValuesTotal(0)));
  for (Eigen::Index i = 0; i < mesh.positions.rows(); ++i) pv.pos[i] = {mesh.positions(i, 0), mesh.positions(i, 1), mesh.positions(i, 2)};
  for (Eigen::Index i = 0; i < mesh.normals.rows(); ++i) pv.nrm[i] = {mesh.normals(i, 0), mesh.normals(i, 1), mesh.normals(i, 2)};
  // UVs ride on the same face-varying channel (render vertices), linearly: a seam stays a seam.
  pv.uvs.resize(mesh.has_uv() ? pv.nrm.size() : 0);
  for (Eigen::Index i = 0; i < mesh.uv.rows(); ++i) pv.uvs[size_t(i)] = {mesh.uv(i, 0), mesh.uv(i, 1)};
  pv.rgb.resize(mesh.has_colors() ? pv.nrm.size() : 0);  // colours too, linearly
  for (Eigen::Index i = 0; i < mesh.colors.rows(); ++i) pv.rgb[size_t(i)] = {mesh.colors(i, 0), mesh.colors(i, 1), mesh.colors(i, 2)};
  Far::PrimvarRefiner primvar(refiner);
  Vec3 *psrc = pv.pos.data(), *nsrc = pv.nrm.data(), *csrc = pv.rgb.data();
  Vec2* usrc = pv.uvs.data();
  for (int level = 1; level <= opt.levels; ++level) {
    Vec3* pdst = psrc + refiner.GetLevel(level - 1).GetNumVertices();
    const int fvar_before = refiner.GetLevel(level - 1).GetNumFVarValues(0);
    Vec3* ndst = nsrc + fvar_before;
    if (opt.scheme == UniformScheme::Linear) primvar.InterpolateVarying(level, psrc, pdst);
    else primvar.Interpolate(level, psrc, pdst);
    primvar.InterpolateFaceVarying(level, nsrc, ndst, 0);
    if (mesh.has_uv()) {
      Vec2* udst = usrc + fvar_before;
      primvar.InterpolateFaceVarying(level, usrc, udst, 0);
      usrc = udst;
    }
    if (mesh.has_colors()) {
      Vec3* cdst = csrc + fvar_before;
      primvar.InterpolateFaceVarying(level, csrc, cdst, 0);
      csrc = cdst;
    }
    psrc = pdst, nsrc = ndst;
  }
  pv.p = psrc, pv.n = nsrc, pv.uv = usrc, pv.c = csrc;
  return pv;
}

// Loop moved the geometry: rebuild render vertices and normals from it with the crease angle.
Mesh loop_mesh(const Far::TopologyLevel& last, const Primvars& pv, const Mesh& mesh) {
  RawMesh raw;
  raw.positions.resize(last.GetNumVertices(), 3);
  for (int v = 0; v < last.GetNumVertices(); ++v) raw.positions.row(v) << pv.p[v].x, pv.p[v].y, pv.p[v].z;
  raw.face_offsets.push_back(0);
  for (int f = 0; f < last.GetNumFaces(); ++f) {
    for (int v : last.GetFaceVertices(f)) raw.face_indices.push_back(v);
    if (mesh.has_uv())
      for (int v : last.GetFaceFVarValues(f, 0)) raw.corner_texcoords.push_back(v);
    raw.face_offsets.push_back(raw.face_indices.size());
  }
  if (mesh.has_colors()) {  // per position, from the first corner at it (as reading a file does)
    raw.colors.setConstant(last.GetNumVertices(), 3, -1);
    raw.colors_linear = true;
    for (int f = 0; f < last.GetNumFaces(); ++f) {
      auto fv = last.GetFaceVertices(f);
      auto fvar = last.GetFaceFVarValues(f, 0);
      for (int k = 0; k < fv.size(); ++k)
        if (raw.colors(fv[k], 0) < 0) raw.colors.row(fv[k]) << pv.c[fvar[k]].x, pv.c[fvar[k]].y, pv.c[fvar[k]].z;
    }
    raw.colors = raw.colors.cwiseMax(0.0).cwiseMin(1.0);
  }
  if (mesh.has_uv()) {
    raw.texcoords.resize(last.GetNumFVarValues(0), 2);
    for (int i = 0; i < last.GetNumFVarValues(0); ++i) raw.texcoords.row(i) << pv.uv[i].u, pv.uv[i].v;
  }
  return build_mesh(raw, "loop subdivision", LoadOptions{mesh.crease_angle_deg});
}

// The linear split keeps the geometry: render vertices are the face-varying values.
Mesh linear_mesh(const Far::TopologyLevel& last, const Primvars& pv, const Mesh& mesh) {
  Mesh out;
  out.normals_from_file = mesh.normals_from_file;
  out.crease_angle_deg = mesh.crease_angle_deg;
  out.positions.resize(last.GetNumVertices(), 3);
  for (int v = 0; v < last.GetNumVertices(); ++v) out.positions.row(v) << pv.p[v].x, pv.p[v].y, pv.p[v].z;
  const int nv = last.GetNumFVarValues(0);
  out.vertex_position.assign(static_cast<size_t>(nv), UINT32_MAX);
  out.normals.resize(nv, 3);
  for (int i = 0; i < nv; ++i) {
    const Eigen::Vector3d n(pv.n[i].x, pv.n[i].y, pv.n[i].z);
    out.normals.row(i) = (n.norm() > 1e-12 ? n.normalized() : Eigen::Vector3d::UnitZ()).transpose();
  }
  if (mesh.has_uv()) {
    out.uv.resize(nv, 2);
    for (int i = 0; i < nv; ++i) out.uv.row(i) << pv.uv[i].u, pv.uv[i].v;
  }
  if (mesh.has_colors()) {
    out.colors.resize(nv, 3);
    for (int i = 0; i < nv; ++i) out.colors.row(i) << pv.c[i].x, pv.c[i].y, pv.c[i].z;
  }
  out.triangles.resize(static_cast<size_t>(last.GetNumFaces()));
  for (int f = 0; f < last.GetNumFaces(); ++f) {
    auto fv = last.GetFaceVertices(f);
    auto fvar = last.GetFaceFVarValues(f, 0);
    for (int k = 0; k < 3; ++k) {
      out.triangles[static_cast<size_t>(f)][static_cast<size_t>(k)] = static_cast<uint32_t>(fvar[k]);
      out.vertex_position[static_cast<size_t>(fvar[k])] = static_cast<uint32_t>(fv[k]);
    }
  }
  out.source_face.resize(out.triangles.size());
  std::iota(out.source_face.begin(), out.source_face.end(), 0u);  // the caller maps them to the input
  return out;
}

}  // namespace

Mesh refine_uniform(const Mesh& mesh, const UniformOptions& opt) {
  if (opt.levels < 1 || opt.levels > 8) throw InputError("uniform refinement: levels must be between 1 and 8, got " + std::to_string(opt.levels));
  if (mesh.has_uv() && static_cast<size_t>(mesh.uv.rows()) != mesh.num_vertices())
    throw InputError("refine: the mesh has " + std::to_string(mesh.uv.rows()) + " UVs for " + std::to_string(mesh.num_vertices()) + " render vertices");
  const std::unique_ptr<Far::TopologyRefiner> refiner = refine_topology(mesh, opt);
  const Primvars pv = interpolate(*refiner, mesh, opt);
  const Far::TopologyLevel& last = refiner->GetLevel(opt.levels);
  Mesh out = opt.scheme == UniformScheme::Loop ? loop_mesh(last, pv, mesh) : linear_mesh(last, pv, mesh);
  // Each face's source_face numbers a face of the last level; follow its parents to the input.
  for (uint32_t& s : out.source_face) {
    int parent = static_cast<int>(s);
    for (int level = opt.levels; level >= 1; --level) parent = refiner->GetLevel(level).GetFaceParentFace(parent);
    s = mesh.source_face[static_cast<size_t>(parent)];
  }
  out.input_triangles = mesh.input_triangles;
  out.input_vertices = mesh.input_vertices;
  out.defects = mesh.defects;
  return out;
}

}  // namespace prtsub
