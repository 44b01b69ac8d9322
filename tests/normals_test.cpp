#include "prtsub/subdiv/normals.h"

#include <gtest/gtest.h>

#include <set>

#include "helpers.h"

namespace prtsub {
namespace {

TEST(Normals, CubeCreasesGiveOneNormalPerSide) {
  Mesh m = test::build(test::cube(), 60.0);
  EXPECT_EQ(m.positions.rows(), 8);
  EXPECT_EQ(m.num_vertices(), 24u);  // 8 corners x 3 faces
  for (size_t v = 0; v < m.num_vertices(); ++v) {
    Eigen::Vector3d n = m.normals.row(static_cast<Eigen::Index>(v)).transpose();
    EXPECT_NEAR(n.cwiseAbs().maxCoeff(), 1.0, 1e-12);  // axis-aligned
  }
  // Each face's corners carry that face's outward normal.
  for (const Triangle& t : m.triangles) {
    Eigen::Vector3d a = m.point(t[0]), b = m.point(t[1]), c = m.point(t[2]);
    Eigen::Vector3d fn = (b - a).cross(c - a).normalized();
    for (uint32_t v : t) EXPECT_NEAR(fn.dot(m.normals.row(v)), 1.0, 1e-12);
  }
}

TEST(Normals, ObtuseCreaseAngleSmoothsTheCube) {
  Mesh m = test::build(test::cube(), 100.0);
  EXPECT_EQ(m.num_vertices(), 8u);
  for (size_t v = 0; v < 8; ++v) {
    // Angle weighting makes the corner normal the diagonal, whatever the triangulation.
    Eigen::Vector3d expect = (m.point(static_cast<uint32_t>(v)) - Eigen::Vector3d::Constant(0.5)).normalized();
    EXPECT_NEAR(expect.dot(m.normals.row(static_cast<Eigen::Index>(v))), 1.0, 1e-12);
  }
}

TEST(Normals, ZeroCreaseAngleIsFlatShading) {
  Mesh m = test::build(test::icosphere(1), 0.0);
  EXPECT_EQ(m.num_vertices(), m.num_faces() * 3);
  for (const Triangle& t : m.triangles) {
    Eigen::Vector3d a = m.point(t[0]), b = m.point(t[1]), c = m.point(t[2]);
    Eigen::Vector3d fn = (b - a).cross(c - a).normalized();
    for (uint32_t v : t) EXPECT_NEAR(fn.dot(m.normals.row(v)), 1.0, 1e-12);
  }
}

TEST(Normals, SmoothSphereNormalsAreNearlyRadial) {
  Mesh m = test::build(test::icosphere(3), 60.0);
  EXPECT_EQ(m.num_vertices(), static_cast<size_t>(m.positions.rows()));
  for (size_t v = 0; v < m.num_vertices(); ++v)
    EXPECT_GT(m.point(static_cast<uint32_t>(v)).normalized().dot(m.normals.row(static_cast<Eigen::Index>(v))), 0.9995);
}

TEST(Normals, BowTieAndNonManifoldEdgesAreNotSmoothedAcross) {
  // Two coplanar triangles touching only at the origin: two fans, two vertices there.
  RowMatrixX3d p(5, 3);
  p << 0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0;
  std::vector<Triangle> tris = {{0, 1, 2}, {0, 3, 4}};
  CornerNormals cn = compute_corner_normals(p, tris, 180.0);
  EXPECT_NE(cn.group[0], cn.group[3]);
  // Three coplanar faces on one edge: never united across it.
  RowMatrixX3d q(5, 3);
  q << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1;
  std::vector<Triangle> fin = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  CornerNormals c2 = compute_corner_normals(q, fin, 180.0);
  std::set<uint32_t> groups_at_0 = {c2.group[0], c2.group[4], c2.group[6]};
  EXPECT_EQ(groups_at_0.size(), 3u);
}

TEST(Normals, ZeroAreaFacesGetAFiniteNormal) {
  RowMatrixX3d p(3, 3);
  p << 0, 0, 0, 1, 0, 0, 2, 0, 0;  // collinear
  CornerNormals cn = compute_corner_normals(p, {{0, 1, 2}}, 60.0);
  EXPECT_TRUE(cn.normals.allFinite());
  EXPECT_NEAR(cn.normals.row(0).norm(), 1.0, 1e-12);
  EXPECT_GT(cn.fallback_normals, 0u);
}

}  // namespace
}  // namespace prtsub
