#include "prtsub/subdiv/uniform.h"

#include <gtest/gtest.h>

#include "helpers.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

double area_of(const Mesh& m) {
  double a = 0;
  for (const Triangle& t : m.triangles) a += triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2]));
  return a;
}

TEST(Uniform, LinearSplitKeepsTheSurfaceAndCarriesSourceFaces) {
  Mesh m = test::build(test::icosphere(1));
  Mesh u = refine_uniform(m, UniformOptions{2, UniformScheme::Linear});
  EXPECT_EQ(u.num_faces(), 80u * 16);
  EXPECT_NEAR(area_of(u), area_of(m), 1e-12 * area_of(m));
  std::vector<Triangle> pos(u.num_faces());
  for (size_t f = 0; f < pos.size(); ++f)
    for (int k = 0; k < 3; ++k) pos[f][k] = u.vertex_position[u.triangles[f][k]];
  EXPECT_EQ(count_edges(pos).boundary, 0u);
  // Every refined face lies inside its source face: its centroid is in that face's plane.
  for (size_t f = 0; f < u.num_faces(); ++f) {
    const Triangle& s = m.triangles[u.source_face[f]];
    Eigen::Vector3d a = m.point(s[0]), n = (m.point(s[1]) - a).cross(m.point(s[2]) - a).normalized();
    Eigen::Vector3d c = (u.point(u.triangles[f][0]) + u.point(u.triangles[f][1]) + u.point(u.triangles[f][2])) / 3;
    EXPECT_NEAR(n.dot(c - a), 0, 1e-12);
  }
}

TEST(Uniform, CreasesRefinePerSideAndLoopSmooths) {
  Mesh cube = test::build(test::cube(), 60);
  Mesh u = refine_uniform(cube, UniformOptions{2, UniformScheme::Linear});
  EXPECT_EQ(u.num_faces(), 12u * 16);
  for (const Triangle& t : u.triangles) {
    Eigen::Vector3d fn = (u.point(t[1]) - u.point(t[0])).cross(u.point(t[2]) - u.point(t[0])).normalized();
    for (uint32_t c : t) EXPECT_NEAR(fn.dot(u.normals.row(c)), 1.0, 1e-9);
  }
  Mesh sphere = test::build(test::icosphere(1));
  Mesh loop = refine_uniform(sphere, UniformOptions{1, UniformScheme::Loop});
  EXPECT_EQ(loop.num_faces(), 320u);
  double moved = 0;
  for (Eigen::Index p = 0; p < loop.positions.rows(); ++p) moved = std::max(moved, std::abs(loop.positions.row(p).norm() - 1));
  EXPECT_GT(moved, 1e-3);  // Loop pulls midpoints off the flat faces
}

TEST(Uniform, UvsAreInterpolatedPerSideOfASeam) {
  const Mesh m = build_mesh(parse_obj(test::seam_square_obj(), "seam.obj"), "seam.obj");
  const Mesh u = refine_uniform(m, UniformOptions{2, UniformScheme::Linear});
  ASSERT_EQ(static_cast<size_t>(u.uv.rows()), u.num_vertices());
  for (size_t f = 0; f < u.num_faces(); ++f)
    for (uint32_t c : u.triangles[f])
      EXPECT_LT((u.uv.row(c).transpose() - test::seam_uv(int(u.source_face[f]), u.point(c))).norm(), 1e-12);
  // Loop moves positions, not UVs: they are still each side's linear interpolation, so they stay
  // inside the hull of the side's input UVs.
  const Mesh loop = refine_uniform(m, UniformOptions{1, UniformScheme::Loop});
  ASSERT_EQ(static_cast<size_t>(loop.uv.rows()), loop.num_vertices());
  EXPECT_TRUE(loop.uv.allFinite());
  EXPECT_GE(loop.uv.minCoeff(), 0.0);
  EXPECT_LE(loop.uv.maxCoeff(), 1.0);
  EXPECT_GT(loop.num_vertices(), static_cast<size_t>(loop.positions.rows()));  // the seam survives
}

}  // namespace
}  // namespace prtsub
