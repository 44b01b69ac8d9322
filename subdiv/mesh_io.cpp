// Mesh readers and the builder that turns what a file says into a Mesh.
//
// Parsers only tokenise; every check lives in build_mesh so all formats fail the same way:
// an empty mesh, a non-finite coordinate or an out-of-range index is an InputError naming
// the file and the first offender. What a real asset tolerably has (collapsed and zero-area
// faces, duplicates, unreferenced vertices, winding conflicts, non-manifold edges) is kept or
// dropped as documented in MeshDefects and counted.
//
// Welding is by exact position (+0 and -0 are equal). Render vertices are keyed by
// (welded position, normal): with file normals, by the normal's exact value; otherwise by the
// crease-aware smoothing group of compute_corner_normals.
#include "prtsub/subdiv/mesh_io.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <array>

#include "prtsub/subdiv/adjacency.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/normals.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

// Splits a buffer into lines and whitespace tokens without copying.
struct LineCursor {
  const std::string& bytes;
  size_t pos = 0;
  size_t line_no = 0;
  bool next(std::string_view& line) {
    if (pos >= bytes.size()) return false;
    size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    line = std::string_view(bytes.data() + pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = eol + 1;
    ++line_no;
    return true;
  }
};

bool next_token(std::string_view& s, std::string_view& tok) {
  size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  if (i == s.size()) return false;
  size_t j = i;
  while (j < s.size() && !std::isspace(static_cast<unsigned char>(s[j]))) ++j;
  tok = s.substr(i, j - i);
  s.remove_prefix(j);
  return true;
}

[[noreturn]] void bad_line(const std::string& path, size_t line_no, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line_no) + ": " + what);
}

double parse_double(std::string_view tok, const std::string& path, size_t line_no) {
  double v = 0;
  auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  if (r.ec != std::errc() || r.ptr != tok.data() + tok.size())
    bad_line(path, line_no, "bad number '" + std::string(tok.substr(0, 32)) + "'");
  return v;
}

int64_t parse_int(std::string_view tok, const std::string& path, size_t line_no) {
  int64_t v = 0;
  auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  if (r.ec != std::errc() || r.ptr != tok.data() + tok.size())
    bad_line(path, line_no, "bad index '" + std::string(tok.substr(0, 32)) + "'");
  return v;
}

void read_xyz(std::string_view& rest, std::vector<double>& out, const std::string& path,
              size_t line_no) {
  std::string_view tok;
  for (int k = 0; k < 3; ++k) {
    if (!next_token(rest, tok)) bad_line(path, line_no, "expected three coordinates");
    out.push_back(parse_double(tok, path, line_no));
  }
}

RowMatrixX3d to_matrix(const std::vector<double>& xyz) {
  RowMatrixX3d m(static_cast<Eigen::Index>(xyz.size() / 3), 3);
  if (!xyz.empty()) std::memcpy(m.data(), xyz.data(), xyz.size() * sizeof(double));
  return m;
}

std::string lower_extension(const std::string& path) {
  size_t dot = path.find_last_of('.');
  size_t slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

RawMesh parse_obj(const std::string& bytes, const std::string& path) {
  std::vector<double> pos, nrm, tex, rgb;
  std::vector<char> coloured;  // per v line: had `r g b` after its coordinates
  RawMesh raw;
  raw.face_offsets.push_back(0);
  bool any_corner_normal = false, any_corner_texcoord = false;
  LineCursor lines{bytes};
  std::string_view line, tok;
  // An OBJ index: 1-based, or negative counting back from the latest of `count` elements.
  auto index = [&](std::string_view t, int64_t count, const char* what) {
    const int64_t i = parse_int(t, path, lines.line_no);
    const int64_t r = i > 0 ? i - 1 : count + i;
    if (i == 0 || r < 0 || r >= count)
      bad_line(path, lines.line_no, std::string(what) + " index " + std::to_string(i) + " out of range (" +
                                        std::to_string(count) + " " + what + "s so far)");
    return r;
  };
  while (lines.next(line)) {
    std::string_view rest = line;
    if (!next_token(rest, tok) || tok[0] == '#') continue;
    if (tok == "v") {
      read_xyz(rest, pos, path, lines.line_no);
      // `v x y z r g b` (MeshLab, ZBrush, many scanners) carries a vertex colour; `v x y z w` a
      // weight, which is not ours.
      std::string_view more = rest, t;
      int n = 0;
      double c[3];
      while (n < 3 && next_token(more, t)) c[n++] = parse_double(t, path, lines.line_no);
      coloured.push_back(n == 3);
      if (n == 3) rgb.insert(rgb.end(), {c[0], c[1], c[2]});
      else rgb.insert(rgb.end(), {1.0, 1.0, 1.0});
    } else if (tok == "vn") {
      read_xyz(rest, nrm, path, lines.line_no);
    } else if (tok == "vt") {
      for (int k = 0; k < 2; ++k) {  // u, and v (0 if absent); a third (w) is not ours
        if (!next_token(rest, tok)) {
          if (k == 0) bad_line(path, lines.line_no, "expected a texture coordinate");
          tex.push_back(0.0);
          break;
        }
        tex.push_back(parse_double(tok, path, lines.line_no));
      }
    } else if (tok == "f") {
      const int64_t nv = static_cast<int64_t>(pos.size() / 3), nn = static_cast<int64_t>(nrm.size() / 3),
                    nt = static_cast<int64_t>(tex.size() / 2);
      while (next_token(rest, tok)) {
        // v, v/t, v//n or v/t/n.
        size_t s1 = tok.find('/');
        int64_t v = parse_int(tok.substr(0, s1), path, lines.line_no);
        if (v == 0) bad_line(path, lines.line_no, "face index 0 (OBJ indices start at 1)");
        raw.face_indices.push_back(v > 0 ? v - 1 : nv + v);
        int64_t n = -1, t = -1;
        if (s1 != std::string_view::npos) {
          size_t s2 = tok.find('/', s1 + 1);
          const std::string_view tt = tok.substr(s1 + 1, s2 == std::string_view::npos ? std::string_view::npos : s2 - s1 - 1);
          if (!tt.empty()) t = index(tt, nt, "texture coordinate"), any_corner_texcoord = true;
          if (s2 != std::string_view::npos && s2 + 1 < tok.size()) n = index(tok.substr(s2 + 1), nn, "normal"), any_corner_normal = true;
        }
        raw.corner_normals.push_back(n);
        raw.corner_texcoords.push_back(t);
      }
      raw.face_offsets.push_back(raw.face_indices.size());
    }
    // o, g, s, usemtl, mtllib, l, p: not geometry we bake.
  }
  raw.positions = to_matrix(pos);
  raw.normals = to_matrix(nrm);
  const size_t with_colour = static_cast<size_t>(std::count(coloured.begin(), coloured.end(), 1));
  if (with_colour > 0) raw.colors = to_matrix(rgb), raw.vertices_without_colour = coloured.size() - with_colour;
  if (!any_corner_normal) raw.corner_normals.clear(), raw.normals.resize(0, 3);
  if (any_corner_texcoord) {
    raw.texcoords.resize(static_cast<Eigen::Index>(tex.size() / 2), 2);
    if (!tex.empty()) std::memcpy(raw.texcoords.data(), tex.data(), tex.size() * sizeof(double));
  } else {
    raw.corner_texcoords.clear();
  }
  return raw;
}

RawMesh parse_off(const std::string& bytes, const std::string& path) {
  LineCursor lines{bytes};
  std::string_view line, tok;
  // Collect the data lines, stripped of comments, as token streams.
  auto next_data = [&](std::string_view& rest) {
    while (lines.next(line)) {
      size_t hash = line.find('#');
      rest = line.substr(0, hash);
      std::string_view probe = rest, t;
      if (next_token(probe, t)) return true;
    }
    return false;
  };
  std::string_view rest;
  if (!next_data(rest) || !next_token(rest, tok) || tok.size() < 3 ||
      tok.substr(tok.size() - 3) != "OFF")
    throw InputError(path + ": not an OFF file (no OFF keyword)");
  const bool has_normals = tok.find('N') != std::string_view::npos;
  if (tok.find('4') != std::string_view::npos || tok.find("ST") != std::string_view::npos)
    throw InputError(path + ": OFF variant '" + std::string(tok) + "' is not supported");
  std::string_view count_tok;
  if (!next_token(rest, count_tok)) {
    if (!next_data(rest) || !next_token(rest, count_tok))
      throw InputError(path + ": OFF file ends before its counts");
  }
  int64_t nv = parse_int(count_tok, path, lines.line_no), nf = 0;
  if (!next_token(rest, tok)) bad_line(path, lines.line_no, "expected vertex and face counts");
  nf = parse_int(tok, path, lines.line_no);
  if (nv < 0 || nf < 0 || static_cast<uint64_t>(nv) > bytes.size() ||
      static_cast<uint64_t>(nf) > bytes.size())
    bad_line(path, lines.line_no, "bad vertex or face count");
  std::vector<double> pos, nrm;
  pos.reserve(static_cast<size_t>(nv) * 3);
  for (int64_t i = 0; i < nv; ++i) {
    if (!next_data(rest))
      throw InputError(path + ": truncated OFF (" + std::to_string(i) + " of " + std::to_string(nv) +
                       " vertices)");
    read_xyz(rest, pos, path, lines.line_no);
    if (has_normals) read_xyz(rest, nrm, path, lines.line_no);
  }
  RawMesh raw;
  raw.face_offsets.push_back(0);
  for (int64_t i = 0; i < nf; ++i) {
    if (!next_data(rest))
      throw InputError(path + ": truncated OFF (" + std::to_string(i) + " of " + std::to_string(nf) +
                       " faces)");
    next_token(rest, tok);
    int64_t n = parse_int(tok, path, lines.line_no);
    if (n < 0 || n > 1000000) bad_line(path, lines.line_no, "bad face size");
    for (int64_t k = 0; k < n; ++k) {
      if (!next_token(rest, tok)) bad_line(path, lines.line_no, "face has fewer indices than its size");
      raw.face_indices.push_back(parse_int(tok, path, lines.line_no));
    }
    raw.face_offsets.push_back(raw.face_indices.size());
  }
  raw.positions = to_matrix(pos);
  raw.normals = to_matrix(nrm);
  return raw;
}

RawMesh parse_stl(const std::string& bytes, const std::string& path) {
  RawMesh raw;
  raw.face_offsets.push_back(0);
  std::vector<double> pos;
  auto starts_solid = [&] {
    size_t i = bytes.find_first_not_of(" \t\r\n");
    return i != std::string::npos && bytes.compare(i, 5, "solid") == 0;
  };
  uint32_t count = 0;
  if (bytes.size() >= 84) std::memcpy(&count, bytes.data() + 80, 4);
  const bool binary = bytes.size() >= 84 && (84 + 50ull * count == bytes.size() || !starts_solid());
  if (binary) {
    if (84 + 50ull * count > bytes.size())
      throw InputError(path + ": truncated binary STL (header says " + std::to_string(count) +
                       " triangles, the file holds " + std::to_string((bytes.size() - 84) / 50) + ")");
    pos.reserve(count * 9ull);
    for (uint32_t t = 0; t < count; ++t) {
      const char* rec = bytes.data() + 84 + 50ull * t + 12;  // skip the facet normal
      for (int k = 0; k < 9; ++k) {
        float v;
        std::memcpy(&v, rec + 4 * k, 4);
        pos.push_back(v);
      }
      for (int k = 0; k < 3; ++k) raw.face_indices.push_back(3ll * t + k);
      raw.face_offsets.push_back(raw.face_indices.size());
    }
  } else {
    if (!starts_solid()) throw InputError(path + ": not an STL file");
    LineCursor lines{bytes};
    std::string_view line, tok;
    size_t in_loop = 0;
    while (lines.next(line)) {
      std::string_view rest = line;
      if (!next_token(rest, tok)) continue;
      if (tok == "vertex") {
        read_xyz(rest, pos, path, lines.line_no);
        raw.face_indices.push_back(static_cast<int64_t>(pos.size() / 3 - 1));
        ++in_loop;
      } else if (tok == "endloop") {
        raw.face_offsets.push_back(raw.face_indices.size());
        in_loop = 0;
      }
    }
    if (in_loop) throw InputError(path + ": truncated ASCII STL (last facet has no endloop)");
  }
  raw.positions = to_matrix(pos);
  return raw;
}

RawMesh parse_ply_mesh(const std::string& bytes, const std::string& path) {
  PlyFile ply = parse_ply(bytes, path);
  const PlyElement* v = ply.element("vertex");
  const PlyElement* f = ply.element("face");
  if (!v) throw InputError(path + ": PLY has no vertex element");
  const std::vector<double>*x = v->scalar("x"), *y = v->scalar("y"), *z = v->scalar("z");
  if (!x || !y || !z) throw InputError(path + ": PLY vertex element lacks x, y or z");
  RawMesh raw;
  raw.positions.resize(static_cast<Eigen::Index>(v->count), 3);
  for (size_t i = 0; i < v->count; ++i)
    raw.positions.row(static_cast<Eigen::Index>(i)) << (*x)[i], (*y)[i], (*z)[i];
  const std::vector<double>*nx = v->scalar("nx"), *ny = v->scalar("ny"), *nz = v->scalar("nz");
  if (nx && ny && nz) {
    raw.normals.resize(static_cast<Eigen::Index>(v->count), 3);
    for (size_t i = 0; i < v->count; ++i)
      raw.normals.row(static_cast<Eigen::Index>(i)) << (*nx)[i], (*ny)[i], (*nz)[i];
  }
  for (auto [un, vn] : {std::pair{"u", "v"}, std::pair{"s", "t"}, std::pair{"texture_u", "texture_v"},
                        std::pair{"texture_s", "texture_t"}}) {
    const std::vector<double>*u = v->scalar(un), *w = v->scalar(vn);
    if (!u || !w) continue;
    raw.texcoords.resize(static_cast<Eigen::Index>(v->count), 2);
    for (size_t i = 0; i < v->count; ++i) raw.texcoords.row(static_cast<Eigen::Index>(i)) << (*u)[i], (*w)[i];
    break;
  }
  for (auto names : {std::array<const char*, 3>{"red", "green", "blue"}, std::array<const char*, 3>{"r", "g", "b"},
                     std::array<const char*, 3>{"diffuse_red", "diffuse_green", "diffuse_blue"}}) {
    const std::vector<double>* c[3] = {v->scalar(names[0]), v->scalar(names[1]), v->scalar(names[2])};
    if (!c[0] || !c[1] || !c[2]) continue;
    raw.colors.resize(static_cast<Eigen::Index>(v->count), 3);
    for (int k = 0; k < 3; ++k) {
      const size_t column = static_cast<size_t>(std::find(v->scalar_names.begin(), v->scalar_names.end(), names[k]) - v->scalar_names.begin());
      const double unit = v->scalar_unit[column];
      for (size_t i = 0; i < v->count; ++i) raw.colors(static_cast<Eigen::Index>(i), k) = (*c[k])[i] / unit;
    }
    break;
  }
  raw.face_offsets.push_back(0);
  if (f) {
    int li = f->list("vertex_indices");
    if (li < 0) li = f->list("vertex_index");
    if (li < 0) throw InputError(path + ": PLY face element lacks vertex_indices");
    const auto& offs = f->list_offsets[static_cast<size_t>(li)];
    const auto& vals = f->list_values[static_cast<size_t>(li)];
    raw.face_indices.reserve(vals.size());
    for (size_t k = 0; k < vals.size(); ++k)
      raw.face_indices.push_back(index_value(vals[k], path + ": a vertex index of a face (list value " + std::to_string(k) + ")"));
    raw.face_offsets.assign(offs.begin(), offs.end());
  }
  return raw;
}

namespace {

// Every check that does not depend on welding: counts, finite values, indices in range.
void validate_raw(const RawMesh& raw, const std::string& path) {
  const size_t nin = static_cast<size_t>(raw.positions.rows());
  const size_t nfaces_in = raw.face_offsets.empty() ? 0 : raw.face_offsets.size() - 1;
  if (nin == 0) throw InputError(path + ": empty mesh (no vertices)");
  if (nfaces_in == 0) throw InputError(path + ": empty mesh (no faces)");
  for (size_t i = 0; i < nin; ++i)
    if (!raw.positions.row(static_cast<Eigen::Index>(i)).allFinite())
      throw InputError(path + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
    else if (raw.positions.row(static_cast<Eigen::Index>(i)).cwiseAbs().maxCoeff() > 1e30)
      throw InputError(path + ": vertex " + std::to_string(i) + " has a coordinate beyond single-precision range");
  for (size_t f = 0; f < nfaces_in; ++f)
    for (size_t c = raw.face_offsets[f]; c < raw.face_offsets[f + 1]; ++c)
      if (raw.face_indices[c] < 0 || static_cast<size_t>(raw.face_indices[c]) >= nin)
        throw InputError(path + ": face " + std::to_string(f) + " refers to vertex " +
                         std::to_string(raw.face_indices[c]) + ", but the file has " +
                         std::to_string(nin) + " vertices (0-based)");
  const bool per_vertex_uv = raw.corner_texcoords.empty() && raw.texcoords.rows() > 0;
  if (per_vertex_uv && raw.texcoords.rows() != raw.positions.rows())
    throw InputError(path + ": " + std::to_string(raw.texcoords.rows()) + " texture coordinates for " +
                     std::to_string(raw.positions.rows()) + " vertices");
  for (Eigen::Index i = 0; i < raw.texcoords.rows(); ++i)
    if (!raw.texcoords.row(i).allFinite())
      throw InputError(path + ": texture coordinate " + std::to_string(i) + " is not finite");
  if (raw.colors.rows() > 0 && raw.colors.rows() != raw.positions.rows())
    throw InputError(path + ": " + std::to_string(raw.colors.rows()) + " vertex colours for " + std::to_string(raw.positions.rows()) + " vertices");
  for (Eigen::Index i = 0; i < raw.colors.rows(); ++i)
    if (!raw.colors.row(i).allFinite() || raw.colors.row(i).minCoeff() < 0 || raw.colors.row(i).maxCoeff() > 1)
      throw InputError(path + ": vertex " + std::to_string(i) + " has a colour outside [0, 1] (" + std::to_string(raw.colors(i, 0)) + ", " +
                       std::to_string(raw.colors(i, 1)) + ", " + std::to_string(raw.colors(i, 2)) + ")");
}

// Welds referenced vertices by exact position, in input order, into mesh.positions; returns
// each input vertex's welded index (UINT32_MAX for unreferenced ones). Equal positions are found
// by sorting the referenced vertices by (x, y, z), compared with < (so +0 and -0 are equal), ties
// by index: each run of equal positions is one welded vertex, numbered where its first vertex
// comes in the file. A sort, not a hash map: a scan's 173k vertices in a few milliseconds rather
// than the map's cache misses.
std::vector<uint32_t> weld_positions(const RawMesh& raw, const std::string& path, Mesh& mesh) {
  const size_t nin = static_cast<size_t>(raw.positions.rows());
  MeshDefects& d = mesh.defects;
  std::vector<char> referenced(nin, 0);
  for (int64_t i : raw.face_indices) referenced[static_cast<size_t>(i)] = 1;
  const RowMatrixX3d& p = raw.positions;
  std::vector<size_t> order;
  order.reserve(nin);
  for (size_t i = 0; i < nin; ++i)
    if (referenced[i]) order.push_back(i);
  auto row = [&](size_t i) { return p.row(static_cast<Eigen::Index>(i)); };
  auto same = [&](size_t a, size_t b) { return row(a) == row(b); };
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    for (Eigen::Index c = 0; c < 3; ++c)
      if (p(Eigen::Index(a), c) != p(Eigen::Index(b), c)) return p(Eigen::Index(a), c) < p(Eigen::Index(b), c);
    return a < b;
  });
  std::vector<size_t> first(nin, 0);  // each referenced vertex's run's first (lowest) index
  for (size_t k = 0; k < order.size(); ++k) first[order[k]] = k > 0 && same(order[k - 1], order[k]) ? first[order[k - 1]] : order[k];
  std::vector<uint32_t> weld(nin, UINT32_MAX);
  std::vector<double> welded;
  welded.reserve(order.size() * 3);
  for (size_t i = 0; i < nin; ++i) {
    if (!referenced[i]) {
      ++d.unreferenced_vertices;
      continue;
    }
    if (first[i] == i) {
      if (welded.size() / 3 >= UINT32_MAX / 4) throw InputError(path + ": too many vertices for 32-bit indices");
      weld[i] = static_cast<uint32_t>(welded.size() / 3);
      welded.insert(welded.end(), {p(Eigen::Index(i), 0), p(Eigen::Index(i), 1), p(Eigen::Index(i), 2)});
    } else {
      weld[i] = weld[first[i]];
      ++d.welded_vertices;
    }
  }
  mesh.positions = to_matrix(welded);
  return weld;
}

// Triangles over welded positions, each with its input corners (for file normals and UVs).
struct PositionTriangles {
  std::vector<Triangle> tri;                     // welded position indices
  std::vector<std::array<size_t, 3>> corner;     // corner slots in raw.face_indices
};

// Fan-triangulates, drops faces that collapse, and numbers source faces.
PositionTriangles triangulate(const RawMesh& raw, const std::vector<uint32_t>& weld, const std::string& path, Mesh& mesh) {
  MeshDefects& d = mesh.defects;
  PositionTriangles out;
  for (size_t f = 0; f + 1 < raw.face_offsets.size(); ++f) {
    size_t b = raw.face_offsets[f], n = raw.face_offsets[f + 1] - b;
    if (n < 3) {
      ++d.degenerate_faces;
      continue;
    }
    if (n > 3) ++d.polygons_triangulated;
    for (size_t k = 1; k + 1 < n; ++k) {
      std::array<size_t, 3> c = {b, b + k, b + k + 1};
      Triangle t;
      for (int j = 0; j < 3; ++j) t[j] = weld[static_cast<size_t>(raw.face_indices[c[j]])];
      uint32_t src = static_cast<uint32_t>(mesh.input_triangles++);
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        ++d.degenerate_faces;
        continue;
      }
      out.tri.push_back(t);
      out.corner.push_back(c);
      mesh.source_face.push_back(src);
    }
  }
  if (out.tri.empty()) throw InputError(path + ": empty mesh (every face is degenerate)");
  return out;
}

// Zero-area and duplicate faces (both kept) and the edge counts.
void count_face_defects(const std::vector<Triangle>& tri_pos, const EdgeAdjacency& adjacency, Mesh& mesh) {
  MeshDefects& d = mesh.defects;
  const double diag = bounds(mesh.positions).diagonal();
  const double min_area = (1e-7 * diag) * (1e-7 * diag);
  // A face is a duplicate when an earlier face has the same three corners in any order: sorted
  // corner triples, sorted, and every face of a run of equal triples but its first.
  std::vector<Triangle> corners(tri_pos.size());
  for (size_t f = 0; f < tri_pos.size(); ++f) {
    const Triangle& t = tri_pos[f];
    if (triangle_area(mesh.positions.row(t[0]), mesh.positions.row(t[1]), mesh.positions.row(t[2])) <= min_area)
      ++d.zero_area_faces;
    corners[f] = t;
    std::sort(corners[f].begin(), corners[f].end());
  }
  std::sort(corners.begin(), corners.end());
  for (size_t k = 1; k < corners.size(); ++k) d.duplicate_faces += corners[k] == corners[k - 1];
  const EdgeCounts ec = count_edges(tri_pos, adjacency);
  d.boundary_edges = ec.boundary;
  d.non_manifold_edges = ec.non_manifold;
  d.winding_conflicts = ec.winding_conflicts;
}

// A render vertex is a position with one normal and one UV: two corners share a render vertex
// when all three agree, bit for bit (the normal by its smoothing group when computed).
struct VertexKey {
  uint32_t position;
  uint64_t a, b;          // group id, or the normal's bits
  uint64_t u = 0, v = 0;  // the UV's bits
  bool operator==(const VertexKey& o) const { return position == o.position && a == o.a && b == o.b && u == o.u && v == o.v; }
};

// The normal of triangle f's corner k: the file's (keyed by its bits) where the file gives a
// valid one, else the computed smoothing group's.
Eigen::Vector3d corner_normal(const RawMesh& raw, const PositionTriangles& pt, const CornerNormals& computed, size_t f, int k,
                              VertexKey& key, Mesh& mesh) {
  Eigen::Vector3d n = computed.normals.row(computed.group[f * 3 + size_t(k)]).transpose();
  key.a = 0, key.b = computed.group[f * 3 + size_t(k)];
  int64_t file_row = -1;
  if (!raw.corner_normals.empty()) file_row = raw.corner_normals[pt.corner[f][size_t(k)]];
  else if (raw.normals.rows() == raw.positions.rows()) file_row = raw.face_indices[pt.corner[f][size_t(k)]];
  if (file_row < 0) return n;
  const Eigen::Vector3d fn = raw.normals.row(static_cast<Eigen::Index>(file_row)).transpose();
  const double len = fn.norm();
  if (!(len > 0 && std::isfinite(len))) {
    ++mesh.defects.invalid_file_normals;
    return n;
  }
  n = fn / len;
  std::memcpy(&key.b, &n.x(), 8);
  uint64_t yz[2];
  std::memcpy(yz, &n.y(), 8);
  std::memcpy(yz + 1, &n.z(), 8);
  key.a = 1 + (yz[0] ^ (yz[1] * 0x9E3779B97F4A7C15ull));
  mesh.normals_from_file = true;
  return n;
}

// Render vertices: computed normals everywhere, then file normals and UVs where the file has them.
void make_render_vertices(const RawMesh& raw, const PositionTriangles& pt, const EdgeAdjacency& adjacency, const LoadOptions& options,
                          Mesh& mesh) {
  const CornerNormals computed = compute_corner_normals(mesh.positions, pt.tri, options.crease_angle_deg, &adjacency);
  const bool per_corner_uv = !raw.corner_texcoords.empty();
  const bool has_uv = per_corner_uv || raw.texcoords.rows() > 0;
  const bool has_colors = raw.colors.rows() > 0;
  std::vector<double> uvs, normals, colors;
  // The render vertices at each position, as a chain through `next` (a position has a handful
  // at most): each corner compares its key with those alone.
  std::vector<uint32_t> chain(static_cast<size_t>(mesh.positions.rows()), UINT32_MAX), next;
  std::vector<VertexKey> keys;
  keys.reserve(pt.tri.size() / 2 + 1), next.reserve(pt.tri.size() / 2 + 1);
  mesh.triangles.resize(pt.tri.size());
  for (size_t f = 0; f < pt.tri.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t p = pt.tri[f][size_t(k)];
      VertexKey key{p, 0, 0};
      const Eigen::Vector3d n = corner_normal(raw, pt, computed, f, k, key, mesh);
      Eigen::Vector2d uv(0, 0);
      if (has_uv) {
        const size_t corner = pt.corner[f][size_t(k)];
        const int64_t row = per_corner_uv ? raw.corner_texcoords[corner] : raw.face_indices[corner];
        if (row >= 0) uv = raw.texcoords.row(static_cast<Eigen::Index>(row)).transpose();
        else ++mesh.defects.corners_without_uv;
        const double u0 = uv.x() == 0.0 ? 0.0 : uv.x(), v0 = uv.y() == 0.0 ? 0.0 : uv.y();  // -0 is 0
        std::memcpy(&key.u, &u0, 8);
        std::memcpy(&key.v, &v0, 8);
      }
      uint32_t v = chain[p];
      while (v != UINT32_MAX && !(keys[v] == key)) v = next[v];
      if (v == UINT32_MAX) {
        v = static_cast<uint32_t>(keys.size());
        keys.push_back(key), next.push_back(chain[p]), chain[p] = v;
        mesh.vertex_position.push_back(p);
        normals.insert(normals.end(), {n.x(), n.y(), n.z()});
        if (has_uv) uvs.insert(uvs.end(), {uv.x(), uv.y()});
        // A render vertex takes the colour of the file vertex of its first corner: colours do
        // not split positions (two file vertices welded at one point keep the first's).
        if (has_colors) {
          const auto row = static_cast<Eigen::Index>(raw.face_indices[pt.corner[f][size_t(k)]]);
          for (int c = 0; c < 3; ++c) colors.push_back(raw.colors_linear ? raw.colors(row, c) : srgb_to_linear(raw.colors(row, c)));
        }
      }
      mesh.triangles[f][size_t(k)] = v;
    }
  }
  mesh.normals = to_matrix(normals);
  if (has_colors) mesh.colors = to_matrix(colors), mesh.defects.vertices_without_colour = raw.vertices_without_colour;
  if (has_uv) {
    mesh.uv.resize(static_cast<Eigen::Index>(uvs.size() / 2), 2);
    std::memcpy(mesh.uv.data(), uvs.data(), uvs.size() * sizeof(double));
  }
}

}  // namespace

Mesh build_mesh(const RawMesh& raw, const std::string& path, const LoadOptions& options) {
  validate_raw(raw, path);
  Mesh mesh;
  mesh.input_vertices = static_cast<size_t>(raw.positions.rows());
  mesh.crease_angle_deg = options.crease_angle_deg;
  const std::vector<uint32_t> weld = weld_positions(raw, path, mesh);
  const PositionTriangles pt = triangulate(raw, weld, path, mesh);
  const EdgeAdjacency adjacency = edge_adjacency(pt.tri);  // for the edge counts and the normals' creases
  count_face_defects(pt.tri, adjacency, mesh);
  make_render_vertices(raw, pt, adjacency, options, mesh);
  return mesh;
}

namespace {

void check_mesh_extension(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext != "obj" && ext != "ply" && ext != "off" && ext != "stl")
    throw InputError(path + ": unknown mesh format '." + ext + "' (expected .obj, .ply, .off or .stl)");
}

}  // namespace

Mesh load_mesh(const std::string& path, const LoadOptions& options) {
  check_mesh_extension(path);
  return parse_mesh(read_file_bytes(path), path, options);
}

Mesh parse_mesh(const std::string& bytes, const std::string& path, const LoadOptions& options) {
  check_mesh_extension(path);
  const std::string ext = lower_extension(path);
  RawMesh raw = ext == "obj"   ? parse_obj(bytes, path)
                : ext == "ply" ? parse_ply_mesh(bytes, path)
                : ext == "off" ? parse_off(bytes, path)
                               : parse_stl(bytes, path);
  return build_mesh(raw, path, options);
}

}  // namespace prtsub
