#include "prtsub/subdiv/mesh_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>

#include "helpers.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"

namespace prtsub {
namespace {

// A unit square as two triangles, in each format, with identical geometry.
const char* kSquareObj = "# square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";

std::string binary_ply(bool big_endian, int declared_faces = 2, size_t cut = 0) {
  std::string h = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face " + std::to_string(declared_faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
  auto put = [&](const void* p, size_t n) {
    std::string b(static_cast<const char*>(p), n);
    if (big_endian) std::reverse(b.begin(), b.end());
    h += b;
  };
  float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (auto& p : v)
    for (float c : p) put(&c, 4);
  int f[2][3] = {{0, 1, 2}, {0, 2, 3}};
  for (auto& t : f) {
    h += char(3);
    for (int i : t) put(&i, 4);
  }
  return cut ? h.substr(0, h.size() - cut) : h;
}

std::string binary_stl(uint32_t declared, size_t triangles) {
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&declared), 4);
  float tri[2][9] = {{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0}};
  for (size_t t = 0; t < triangles; ++t) {
    float normal[3] = {0, 0, 1};
    s.append(reinterpret_cast<const char*>(normal), 12);
    s.append(reinterpret_cast<const char*>(tri[t % 2]), 36);
    s.append(2, '\0');
  }
  return s;
}

void expect_square(const Mesh& m) {
  EXPECT_EQ(m.input_triangles, 2u);
  EXPECT_EQ(m.num_faces(), 2u);
  EXPECT_EQ(m.positions.rows(), 4);
  EXPECT_EQ(m.num_vertices(), 4u);  // flat: one smoothing group per position
  for (size_t v = 0; v < m.num_vertices(); ++v) EXPECT_NEAR(m.normals(static_cast<Eigen::Index>(v), 2), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.positions.col(0).sum(), 2.0);
  EXPECT_EQ(m.defects.boundary_edges, 4u);
}

class MeshIo : public ::testing::Test {
 protected:
  test::TempDir dir;
  std::string file(const std::string& name, const std::string& bytes) {
    std::string p = dir.path(name);
    test::write_text(p, bytes);
    return p;
  }
  // The error must name the file and contain `what`.
  template <class E = InputError>
  void expect_error(const std::string& path, const std::string& what) {
    try {
      load_mesh(path);
      ADD_FAILURE() << "no error for " << path;
    } catch (const E& e) {
      std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
    }
  }
};

TEST_F(MeshIo, EveryFormatReadsTheSameSquare) {
  expect_square(load_mesh(file("a.obj", kSquareObj)));
  expect_square(load_mesh(file("a.OBJ", kSquareObj)));
  expect_square(load_mesh(file("a.off", "OFF\n# c\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")));
  expect_square(load_mesh(file("a.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                        "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
                                        "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")));
  expect_square(load_mesh(file("le.ply", binary_ply(false))));
  expect_square(load_mesh(file("be.ply", binary_ply(true))));
  expect_square(load_mesh(file("b.stl", binary_stl(2, 2))));
  expect_square(load_mesh(file("a.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
                                        "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\n"
                                        "vertex 0 1 0\nendloop\nendfacet\nendsolid s\n")));
}

TEST_F(MeshIo, PolygonsAreFanTriangulatedAndNegativeIndicesResolve) {
  Mesh m = load_mesh(file("q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\nf -5 -4 -3 -1 -2\n"));
  EXPECT_EQ(m.input_triangles, 3u);
  EXPECT_EQ(m.num_faces(), 3u);
  EXPECT_EQ(m.defects.polygons_triangulated, 1u);
  std::vector<uint32_t> src(m.source_face.begin(), m.source_face.end());
  EXPECT_EQ(src, (std::vector<uint32_t>{0, 1, 2}));
}

TEST_F(MeshIo, ObjNormalsAreUsedAsGiven) {
  // Per-corner normals that differ from the face normal must survive unchanged (normalised).
  Mesh m = load_mesh(file("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 0.6 0 0.8\nf 1//1 2//2 3//1\n"));
  EXPECT_TRUE(m.normals_from_file);
  ASSERT_EQ(m.num_vertices(), 3u);
  EXPECT_NEAR(m.normals(1, 0), 0.6, 1e-12);
  EXPECT_NEAR(m.normals(1, 2), 0.8, 1e-12);
  EXPECT_NEAR(m.normals(0, 2), 1.0, 1e-12);
}

TEST_F(MeshIo, PlyNormalsAreUsedAsGiven) {
  Mesh m = load_mesh(file("n.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                                   "property double z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                                   "element face 1\nproperty list uchar uint vertex_index\nend_header\n"
                                   "0 0 0 0 0 1\n1 0 0 0 1 0\n0 1 0 1 0 0\n3 0 1 2\n"));
  EXPECT_TRUE(m.normals_from_file);
  EXPECT_NEAR(m.normals(1, 1), 1.0, 1e-12);
  EXPECT_NEAR(m.normals(2, 0), 1.0, 1e-12);
}

TEST_F(MeshIo, TextureCoordinatesMakeSeamsLikeCreases) {
  // OBJ vt per corner: the two diagonal corners have one UV per side, so 4 positions and 6
  // render vertices; each corner keeps the UV the file gave it.
  Mesh m = load_mesh(file("seam.obj", test::seam_square_obj()));
  ASSERT_TRUE(m.has_uv());
  EXPECT_EQ(m.positions.rows(), 4);
  EXPECT_EQ(m.num_vertices(), 6u);
  ASSERT_EQ(static_cast<size_t>(m.uv.rows()), m.num_vertices());
  for (size_t f = 0; f < 2; ++f)
    for (uint32_t v : m.triangles[f])
      EXPECT_EQ((m.uv.row(v).transpose() - test::seam_uv(int(f), m.point(v))).norm(), 0.0);
  EXPECT_EQ(m.defects.corners_without_uv, 0u);
  // Shared UVs on the diagonal: no seam, one render vertex per position.
  Mesh joined = load_mesh(file("j.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                        "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"));
  EXPECT_EQ(joined.num_vertices(), 4u);
  // A face without vt in a mesh with UVs: (0, 0), counted.
  Mesh partial = load_mesh(file("p.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0.5 0.25\nf 1/1 2/1 3/1\nf 1 3 4\n"));
  EXPECT_EQ(partial.defects.corners_without_uv, 3u);
  EXPECT_EQ(partial.num_vertices(), 6u);  // corners 1 and 3 differ in UV between the faces
  // PLY per-vertex u v (also s t): one UV per position.
  Mesh ply = load_mesh(file("uv.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                                      "property double z\nproperty float s\nproperty float t\n"
                                      "element face 1\nproperty list uchar uint vertex_index\nend_header\n"
                                      "0 0 0 0.25 0.5\n1 0 0 0.75 0.5\n0 1 0 0.25 1\n3 0 1 2\n"));
  ASSERT_TRUE(ply.has_uv());
  EXPECT_EQ(ply.uv(1, 0), 0.75);
  EXPECT_EQ(ply.uv(2, 1), 1.0);
  // Without UVs in the file there are none, rather than zeros.
  EXPECT_FALSE(load_mesh(file("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).has_uv());
  // Bad UVs are an error naming the file.
  expect_error(file("r.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n"), "texture coordinate index 2 out of range");
  expect_error(file("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt nan 0\nf 1/1 2/1 3/1\n"), "texture coordinate 0 is not finite");
  expect_error(file("e.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt\nf 1/1 2/1 3/1\n"), "expected a texture coordinate");
}

TEST_F(MeshIo, VertexColoursAreDecodedFromSrgbToLinear) {
  // PLY uchar: 255 is 1, 0 is 0, and 188 decodes by the sRGB curve ((188/255 + 0.055)/1.055)^2.4.
  const std::string ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                          "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 2\n"
                          "property list uchar int vertex_indices\nend_header\n"
                          "0 0 0 255 0 188\n1 0 0 255 0 188\n1 1 0 255 0 188\n0 1 0 10 20 30\n3 0 1 2\n3 0 2 3\n";
  const Mesh m = load_mesh(file("c.ply", ply));
  ASSERT_TRUE(m.has_colors());
  ASSERT_EQ(static_cast<size_t>(m.colors.rows()), m.num_vertices());
  const double c188 = std::pow((188 / 255.0 + 0.055) / 1.055, 2.4), c10 = 10 / 255.0 / 12.92;
  bool saw_last = false;
  for (uint32_t v = 0; v < m.num_vertices(); ++v) {
    if (m.point(v) == Eigen::Vector3d(0, 1, 0)) {
      EXPECT_NEAR(m.colors(v, 0), c10, 1e-15);
      saw_last = true;
      continue;
    }
    EXPECT_EQ(m.colors(v, 0), 1.0);
    EXPECT_EQ(m.colors(v, 1), 0.0);
    EXPECT_NEAR(m.colors(v, 2), c188, 1e-15);
  }
  EXPECT_TRUE(saw_last);
  // PLY floats in [0, 1] and OBJ `v x y z r g b` are sRGB-encoded too; a `v` line without one
  // in a coloured OBJ is white and counted.
  const Mesh o = load_mesh(file("c.obj", "v 0 0 0 0.5 0.5 0.5\nv 1 0 0 0.5 0.5 0.5\nv 1 1 0\nf 1 2 3\n"));
  ASSERT_TRUE(o.has_colors());
  EXPECT_EQ(o.defects.vertices_without_colour, 1u);
  const double half = std::pow((0.5 + 0.055) / 1.055, 2.4);
  for (uint32_t v = 0; v < o.num_vertices(); ++v) EXPECT_NEAR(o.colors(v, 1), o.point(v).y() > 0 ? 1.0 : half, 1e-15);
  EXPECT_FALSE(load_mesh(file("plain.obj", kSquareObj)).has_colors());
  EXPECT_FALSE(load_mesh(file("w.obj", "v 0 0 0 1\nv 1 0 0 1\nv 1 1 0 1\nf 1 2 3\n")).has_colors());  // a weight, not a colour
  expect_error(file("bright.obj", "v 0 0 0 2 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"), "has a colour outside [0, 1]");
}

TEST_F(MeshIo, WeldsExactPositionsIncludingSignedZero) {
  // Two triangles whose shared edge is written twice, once with -0.
  Mesh m = load_mesh(file("w.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv -0 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 4 5 6\n"));
  EXPECT_EQ(m.positions.rows(), 4);
  EXPECT_EQ(m.defects.welded_vertices, 2u);
  EXPECT_EQ(m.defects.boundary_edges, 4u);
}

TEST_F(MeshIo, WeldedPositionsAreNumberedInFileOrderAndRepeatsCountOnce) {
  // Positions repeated out of order: welded positions keep the order of their first vertex in
  // the file, whatever order the weld finds them in; a face written three times (any rotation or
  // winding) is two duplicates; render vertices follow the faces' corners.
  Mesh m = load_mesh(file("o.obj",
                          "v 5 5 0\nv 0 0 0\nv 5 0 0\nv 0 0 0\nv 5 5 0\nv 0 5 0\nv 5 0 0\n"
                          "f 1 2 3\nf 5 4 6\nf 3 1 4\nf 2 7 1\n"));
  ASSERT_EQ(m.positions.rows(), 4);
  EXPECT_EQ(m.positions.row(0), Eigen::RowVector3d(5, 5, 0));
  EXPECT_EQ(m.positions.row(1), Eigen::RowVector3d(0, 0, 0));
  EXPECT_EQ(m.positions.row(2), Eigen::RowVector3d(5, 0, 0));
  EXPECT_EQ(m.positions.row(3), Eigen::RowVector3d(0, 5, 0));
  EXPECT_EQ(m.defects.welded_vertices, 3u);
  EXPECT_EQ(m.defects.duplicate_faces, 2u);  // faces 3 and 4 repeat face 1
  EXPECT_EQ(m.vertex_position[m.triangles[0][0]], 0u);
  EXPECT_EQ(m.vertex_position[m.triangles[0][1]], 1u);
  EXPECT_EQ(m.vertex_position[m.triangles[1][2]], 3u);
}

TEST_F(MeshIo, ToleratedDefectsAreCounted) {
  std::string obj =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 9 9 9\nv 2 0 0\nv 0.5 0 0\n"
      "f 1 2 3\n"   // base
      "f 1 3 4\n"   // neighbour, consistent winding
      "f 3 2 1\n"   // back-to-back twin of face 1: duplicate
      "f 1 2 5\n"   // third face on edge 1-2: non-manifold (and a winding conflict with face 1)
      "f 1 1 2\n"   // collapsed: dropped
      "f 1 7 8\n";  // zero area (collinear)
  Mesh m = load_mesh(file("d.obj", obj));
  EXPECT_EQ(m.input_triangles, 6u);
  EXPECT_EQ(m.num_faces(), 5u);
  EXPECT_EQ(m.defects.degenerate_faces, 1u);
  EXPECT_EQ(m.defects.duplicate_faces, 1u);
  EXPECT_EQ(m.defects.zero_area_faces, 1u);
  EXPECT_EQ(m.defects.unreferenced_vertices, 1u);  // v 9 9 9
  EXPECT_GE(m.defects.non_manifold_edges, 1u);
  // source_face skips the collapsed face.
  EXPECT_EQ(m.source_face.back(), 5u);
}

TEST_F(MeshIo, InconsistentWindingIsCounted) {
  Mesh m = load_mesh(file("wind.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 4 3\n"));
  EXPECT_EQ(m.defects.winding_conflicts, 1u);
}

TEST_F(MeshIo, BadInputIsOneLineNamingTheFile) {
  expect_error<IoError>(dir.path("missing.obj"), "cannot open");
  expect_error(file("x.xyz", kSquareObj), "unknown mesh format");
  expect_error(file("e.obj", "# nothing\n"), "empty mesh");
  expect_error(file("v.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "no faces");
  expect_error(file("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"), "non-finite");
  expect_error(file("inf.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n"), "non-finite");
  expect_error(file("idx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), "refers to vertex 3");
  expect_error(file("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n"), "refers to vertex -1");
  expect_error(file("idx.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"), "refers to vertex 7");
  expect_error(file("bad.obj", "v 0 0 zero\n"), "bad number");
  expect_error(file("cut.ply", binary_ply(false, 2, 5)), "truncated");
  expect_error(file("lie.ply", binary_ply(false, 2000000)), "truncated");
  expect_error(file("cut.stl", binary_stl(2, 1)), "truncated");
  expect_error(file("cut.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n"), "truncated");
  expect_error(file("hdr.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"), "end_header");
  expect_error(file("noply.ply", "solid\n"), "not a PLY");
  expect_error(file("asc.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                               "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n"), "truncated");
  expect_error(file("d.obj", "v 0 0 0\nv 1 0 0\nf 1 2 2\n"), "every face is degenerate");
  expect_error(file("huge.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                "end_header\n1e39 0 0\n3 0 0 0\n"), "single-precision range");
}

TEST_F(MeshIo, RandomBytesNeverCrash) {
  // Corrupt real files at random positions: every outcome is a mesh or an InputError.
  std::string ply = binary_ply(false);
  for (uint64_t s = 0; s < 300; ++s) {
    std::string bytes = ply;
    Rng rng(s, 3);
    for (int k = 0; k < 4; ++k) bytes[static_cast<size_t>(rng.next() % bytes.size())] = static_cast<char>(rng.next());
    std::string p = file("fuzz" + std::to_string(s % 3) + (s % 2 ? ".ply" : ".obj"), s % 2 ? bytes : std::string(kSquareObj).substr(0, rng.next() % 60));
    try {
      Mesh m = load_mesh(p);
      EXPECT_TRUE(m.positions.allFinite());
      for (auto& t : m.triangles)
        for (uint32_t v : t) EXPECT_LT(v, m.num_vertices());
    } catch (const InputError&) {
    }
  }
}

// A header may claim any count: an element without properties holds no bytes, so reading it
// must not count to 10^18 (it did: a 60-byte file kept the reader busy for hours). Declaring an
// element twice is an error, not a second, empty element to spin over.
TEST(MeshIoHardening, ClaimedCountsCannotMakeTheReaderSpin) {
  const std::string empty_rows = "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000000000\nend_header\n";
  try {
    parse_ply_mesh(empty_rows, "spin.ply");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("spin.ply: PLY element 'vertex' declares 1000000000000000000 rows but no properties"),
              std::string::npos)
        << e.what();
  }
  const std::string twice = binary_ply(false) ;
  std::string dup = twice;
  dup.insert(dup.find("end_header"), "element face 2147483648\n");
  try {
    parse_ply_mesh(dup, "dup.ply");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("declares element 'face' twice"), std::string::npos) << e.what();
  }
}

// Indices stored as numbers must be integers: 2.5 is not vertex 2, and NaN or 1e300 must not
// reach an integer conversion (undefined behaviour).
TEST(MeshIoHardening, FractionalAndNonFiniteIndicesAreErrors) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                           "element face 1\nproperty list uchar float vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  for (const char* face : {"3 0 1 2.5\n", "3 0 1 nan\n", "3 0 1 1e300\n", "3 0 1 -inf\n"}) {
    try {
      parse_ply_mesh(head + face, "idx.ply");
      ADD_FAILURE() << face;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("is not an integer index"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(parse_ply_mesh(head + "3 0 1 2\n", "ok.ply").face_indices, (std::vector<int64_t>{0, 1, 2}));  // 2.0 is fine
  EXPECT_THROW(index_value(4.5, "x"), InputError);
  EXPECT_EQ(index_value(-3, "x"), -3);
}

}  // namespace
}  // namespace prtsub
