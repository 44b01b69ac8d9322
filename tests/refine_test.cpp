#include "prtsub/subdiv/refine.h"

#include <gtest/gtest.h>

#include <map>
#include <set>

#include "helpers.h"
#include "prtsub/subdiv/uniform.h"
#include "prtsub/subdiv/random.h"

namespace prtsub {
namespace {

// A scalar signal: a sharp step across the plane x = x0 (a "shadow boundary"), evaluated at
// positions. Records every vertex refinement creates.
struct StepSignal : RefinementSignal {
  double x0 = 0.3, width = 0.02;
  std::vector<NewVertex> created;
  double at(const Eigen::Vector3d& p) const { return 1 / (1 + std::exp(-(p.x() - x0) / width)); }
  double edge_error(const EdgeView& e) const override { return std::abs(e.va[0] - e.vb[0]); }
  void compute_values(const std::vector<NewVertex>& batch, const RowMatrixXd&, RowMatrixXd& values) override {
    for (size_t i = 0; i < batch.size(); ++i) values(static_cast<Eigen::Index>(i), 0) = at(batch[i].position);
    created.insert(created.end(), batch.begin(), batch.end());
  }
  RowMatrixXd initial(const Mesh& m) const {
    RowMatrixXd v(static_cast<Eigen::Index>(m.num_vertices()), 1);
    for (uint32_t i = 0; i < m.num_vertices(); ++i) v(i, 0) = at(m.point(i));
    return v;
  }
};

TEST(Refine, ClosedMeshStaysConformingWithExactBudgetAndArea) {
  Mesh m = test::build(test::icosphere(1));
  StepSignal s;
  RowMatrixXd v = s.initial(m);
  const double area = test::total_area(m);
  RefineStats st = refine_adaptive(m, v, s, RefineOptions{1000, 16, 0});
  EXPECT_TRUE(st.warning.empty()) << st.warning;
  EXPECT_EQ(m.num_faces(), 1000u);
  EdgeCounts e = test::position_edges(m);
  EXPECT_EQ(e.boundary, 0u);  // a T-junction would open boundary edges
  EXPECT_EQ(e.non_manifold, 0u);
  EXPECT_EQ(e.winding_conflicts, 0u);  // orientation kept
  EXPECT_EQ(static_cast<long>(m.positions.rows()) - static_cast<long>(e.edges) + static_cast<long>(m.num_faces()), 2);
  EXPECT_NEAR(test::total_area(m), area, 1e-12 * area);
  // Every new vertex is the midpoint of its parents and carries the signal's value.
  ASSERT_EQ(st.new_vertices, s.created.size());
  for (const NewVertex& nv : s.created) {
    EXPECT_LT((nv.position - 0.5 * (m.point(nv.a) + m.point(nv.b))).norm(), 1e-15);
    EXPECT_EQ(v(nv.index, 0), s.at(nv.position));
  }
  EXPECT_EQ(v.rows(), static_cast<Eigen::Index>(m.num_vertices()));
  EXPECT_GE(st.min_angle_after_deg, 0.5 * st.min_angle_before_deg);
}

TEST(Refine, RefinesWhereTheSignalChanges) {
  Mesh m = test::build(test::grid(8));
  StepSignal s;
  RowMatrixXd v = s.initial(m);
  refine_adaptive(m, v, s, RefineOptions{600, 8, 0});
  size_t near = 0;
  for (const NewVertex& nv : s.created) near += std::abs(nv.position.x() - s.x0) < 0.15;
  EXPECT_GT(near, s.created.size() * 8 / 10) << near << " of " << s.created.size();
}

TEST(Refine, ABatchIsAtMostASixteenthOfTheFaces) {
  // 8 faces to 400: with batches of 256 the first would split on the 8 starting keys alone.
  // The cap grows the batch with the mesh: 1 face while under 32, then F/16.
  Mesh m = test::build(test::grid(2));
  StepSignal s;
  RowMatrixXd v = s.initial(m);
  RefineStats st = refine_adaptive(m, v, s, RefineOptions{400, 256, 0});
  EXPECT_EQ(m.num_faces(), 400u);
  // Uncapped, one or two batches of 256 pops would do; capped, it takes 29.
  EXPECT_GT(st.batches, 10u) << st.faces_popped << " faces popped";
}

TEST(Refine, ABatchIsAtMostASixtyFourthOfWhatTheRunAdds) {
  // 2,048 faces and 128 more to add: the sixteenth of the faces would be one batch of 128 pops,
  // split on the starting keys, which spread it over every face the step crosses and their
  // neighbours. A sixty-fourth of the 128 (two pops a batch) lets the splits go deep at the step.
  Mesh m = test::build(test::grid(32));
  StepSignal s;
  s.width = 0.002;
  RowMatrixXd v = s.initial(m);
  RefineStats st = refine_adaptive(m, v, s, RefineOptions{2048 + 128, 256, 0});
  EXPECT_EQ(m.num_faces(), 2048u + 128u);
  size_t near = 0;
  for (const NewVertex& nv : s.created) near += std::abs(nv.position.x() - s.x0) < 0.5 / 32;
  // Every new vertex within half a starting cell of the step; with one batch of 128, 32 of 64.
  EXPECT_EQ(near, s.created.size());
  EXPECT_GE(st.batches, 32u);
}

TEST(Refine, BudgetParityAndTrivialBudgets) {
  StepSignal s;
  {  // below the input: unchanged, with a warning
    Mesh m = test::build(test::icosphere(1));
    RowMatrixXd v = s.initial(m);
    RefineStats st = refine_adaptive(m, v, s, RefineOptions{50, 16, 0});
    EXPECT_EQ(m.num_faces(), 80u);
    EXPECT_FALSE(st.warning.empty());
  }
  {  // closed: odd budgets stop one short and say why; one interior split adds two
    Mesh m = test::build(test::icosphere(1));
    RowMatrixXd v = s.initial(m);
    RefineStats st = refine_adaptive(m, v, s, RefineOptions{101, 16, 0});
    EXPECT_EQ(m.num_faces(), 100u);
    EXPECT_NE(st.warning.find("closed"), std::string::npos) << st.warning;
    Mesh m2 = test::build(test::icosphere(1));
    RowMatrixXd v2 = s.initial(m2);
    refine_adaptive(m2, v2, s, RefineOptions{82, 16, 0});
    EXPECT_EQ(m2.num_faces(), 82u);
  }
  for (size_t budget : {129u, 130u, 131u, 333u}) {  // with a boundary: exact, odd or even
    Mesh m = test::build(test::grid(8));
    RowMatrixXd v = s.initial(m);
    RefineStats st = refine_adaptive(m, v, s, RefineOptions{budget, 4, 0});
    EXPECT_EQ(m.num_faces(), budget);
    EXPECT_TRUE(st.warning.empty()) << st.warning;
    EdgeCounts e = test::position_edges(m);
    EXPECT_EQ(e.boundary, 32u + st.boundary_splits);  // the outline gained only split halves
  }
}

TEST(Refine, FacesWithoutErrorWaitForFacesWithError) {
  // Signal 1 at one interior grid vertex, 0 elsewhere: only its faces have error.
  RawMesh g = test::grid(6);
  Mesh m = test::build(g);
  struct Spike : RefinementSignal {
    Eigen::Vector3d at = Eigen::Vector3d(0.5, 0.5, 0);
    std::vector<NewVertex> created;
    double edge_error(const EdgeView& e) const override { return std::abs(e.va[0] - e.vb[0]); }
    void compute_values(const std::vector<NewVertex>& b, const RowMatrixXd& parents, RowMatrixXd& out) override {
      out = parents;
      created.insert(created.end(), b.begin(), b.end());
    }
  } s;
  RowMatrixXd v(static_cast<Eigen::Index>(m.num_vertices()), 1);
  for (uint32_t i = 0; i < m.num_vertices(); ++i) v(i, 0) = (m.point(i) - s.at).norm() < 1e-9 ? 1.0 : 0.0;
  refine_adaptive(m, v, s, RefineOptions{m.num_faces() + 12, 1, 0});
  for (const NewVertex& nv : s.created) EXPECT_LT((nv.position - s.at).norm(), 1.0 / 6 * 1.5) << nv.position.transpose();
}

TEST(Refine, CreasesKeepOneVertexPerSideAndNormalsStayExact) {
  Mesh m = test::build(test::cube(), 60.0);  // every cube edge is a crease
  StepSignal s;
  s.x0 = 0.5, s.width = 0.2;
  RowMatrixXd v = s.initial(m);
  RowMatrixXd uv(static_cast<Eigen::Index>(m.num_vertices()), 2);
  for (uint32_t i = 0; i < m.num_vertices(); ++i) uv.row(i) << m.point(i).x(), 2 * m.point(i).y() + 1;
  refine_adaptive(m, v, s, RefineOptions{200, 8, 0}, &uv);
  EXPECT_EQ(m.num_faces(), 200u);
  EXPECT_EQ(test::position_edges(m).boundary, 0u);
  // Normals stay the faces' axis-aligned normals; each face's corners agree with its normal.
  for (const Triangle& t : m.triangles) {
    Eigen::Vector3d fn = (m.point(t[1]) - m.point(t[0])).cross(m.point(t[2]) - m.point(t[0])).normalized();
    for (uint32_t c : t) EXPECT_NEAR(fn.dot(m.normals.row(c)), 1.0, 1e-12);
  }
  // A position on a cube edge (two coordinates in {0,1}) has one render vertex per side.
  std::map<uint32_t, int> per_position;
  for (uint32_t i = 0; i < m.num_vertices(); ++i) ++per_position[m.vertex_position[i]];
  for (auto [p, n] : per_position) {
    Eigen::Vector3d x = m.positions.row(p);
    int on_faces = 0;
    for (int c = 0; c < 3; ++c) on_faces += (x[c] == 0 || x[c] == 1);
    if (on_faces >= 2) {
      EXPECT_GE(n, on_faces) << x.transpose();
    }
  }
  // Linear attributes are reproduced exactly by midpoint interpolation.
  for (uint32_t i = 0; i < m.num_vertices(); ++i) {
    EXPECT_NEAR(uv(i, 0), m.point(i).x(), 1e-15);
    EXPECT_NEAR(uv(i, 1), 2 * m.point(i).y() + 1, 1e-15);
  }
}

TEST(Refine, VertexColoursRefineAsLinearAttributes) {
  // A colour that is an affine function of position is reproduced exactly at every new vertex,
  // by adaptive and by uniform (linear) refinement alike.
  RawMesh raw = test::cube();
  raw.colors.resize(raw.positions.rows(), 3);
  for (Eigen::Index i = 0; i < raw.positions.rows(); ++i)
    raw.colors.row(i) << raw.positions(i, 0), 0.5 * raw.positions(i, 1) + 0.25, 1 - raw.positions(i, 2);
  raw.colors_linear = true;
  const Mesh base = test::build(raw, 60.0);
  ASSERT_TRUE(base.has_colors());
  auto expect_affine = [](const Mesh& m, const char* what) {
    ASSERT_EQ(static_cast<size_t>(m.colors.rows()), m.num_vertices()) << what;
    for (uint32_t i = 0; i < m.num_vertices(); ++i) {
      const Eigen::Vector3d p = m.point(i);
      EXPECT_NEAR(m.colors(i, 0), p.x(), 1e-12) << what;
      EXPECT_NEAR(m.colors(i, 1), 0.5 * p.y() + 0.25, 1e-12) << what;
      EXPECT_NEAR(m.colors(i, 2), 1 - p.z(), 1e-12) << what;
    }
  };
  Mesh m = base;
  StepSignal s;
  s.x0 = 0.5, s.width = 0.2;
  RowMatrixXd v = s.initial(m);
  refine_adaptive(m, v, s, RefineOptions{200, 8, 0});
  EXPECT_EQ(m.num_faces(), 200u);
  expect_affine(m, "adaptive");
  UniformOptions u;
  u.levels = 2;
  expect_affine(refine_uniform(base, u), "uniform");
}

TEST(Refine, UvSeamsRefinePerSideWithMidpointUvs) {
  // The seamed square, refined across a step: every corner's UV is its side's affine map of its
  // position (midpoints of linear UVs are exact), so a vertex on the seam has one UV per side.
  Mesh m = build_mesh(parse_obj(test::seam_square_obj(), "seam.obj"), "seam.obj");
  StepSignal s;
  s.x0 = 0.45, s.width = 0.05;
  RowMatrixXd v = s.initial(m);
  refine_adaptive(m, v, s, RefineOptions{60, 4, 0});
  EXPECT_EQ(m.num_faces(), 60u);
  ASSERT_EQ(static_cast<size_t>(m.uv.rows()), m.num_vertices());
  std::map<uint32_t, std::set<int>> sides_at;  // position on the open diagonal -> sides seen
  for (size_t f = 0; f < m.num_faces(); ++f)
    for (uint32_t c : m.triangles[f]) {
      const int side = int(m.source_face[f]);
      EXPECT_LT((m.uv.row(c).transpose() - test::seam_uv(side, m.point(c))).norm(), 1e-14);
      const Eigen::Vector3d p = m.point(c);
      if (p.x() == p.y() && p.x() > 0 && p.x() < 1) sides_at[m.vertex_position[c]].insert(side);
    }
  ASSERT_FALSE(sides_at.empty());  // the diagonal was split
  for (auto& [p, sides] : sides_at) {
    EXPECT_EQ(sides.size(), 2u);
    size_t render = 0;
    for (uint32_t i = 0; i < m.num_vertices(); ++i) render += m.vertex_position[i] == p;
    EXPECT_EQ(render, 2u);  // one render vertex per side
  }
}

// Position edges with their face counts.
std::map<std::pair<uint32_t, uint32_t>, int> edge_valences(const Mesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> out;
  for (const Triangle& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = m.vertex_position[t[k]], b = m.vertex_position[t[(k + 1) % 3]];
      ++out[{std::min(a, b), std::max(a, b)}];
    }
  return out;
}

// Rivara's bound, as the issue states it: over output faces whose input face was not already
// below 1°, the smallest angle is at least half the smallest such input angle.
void expect_rivara_bound(const std::vector<double>& input_angles, const Mesh& out) {
  double input_min = 180;
  for (double a : input_angles)
    if (a >= 1) input_min = std::min(input_min, a);
  const std::vector<double> angles = face_min_angles_deg(out);
  double out_min = 180;
  for (size_t f = 0; f < angles.size(); ++f)
    if (input_angles[out.source_face[f]] >= 1) out_min = std::min(out_min, angles[f]);
  EXPECT_GE(out_min, 0.5 * input_min) << "input " << input_min << "°";
}

TEST(Refine, NonManifoldEdgesAreSplitInAllTheirFaces) {
  // Three triangles on the edge (0,0,0)-(1,0,0): a fin.
  RawMesh fin;
  fin.positions.resize(5, 3);
  fin.positions << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1;
  fin.face_indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  fin.face_offsets = {0, 3, 6, 9};
  Mesh m = test::build(fin);
  const double area = test::total_area(m);
  StepSignal s;
  s.x0 = 0.5;
  RowMatrixXd v = s.initial(m);
  RefineStats st = refine_adaptive(m, v, s, RefineOptions{40, 4, 0});
  EXPECT_EQ(st.non_manifold_edges, 1u);
  EXPECT_EQ(st.non_manifold_edges_kept, 0u);
  EXPECT_GT(st.non_manifold_splits, 0u);
  EXPECT_EQ(m.num_faces(), 40u);
  EXPECT_NEAR(test::total_area(m), area, 1e-12 * area);
  // Conforming: every edge on the fin's segment (y = z = 0) has all three faces, every other
  // edge two, or one on the outline (each edge of the outline lies on an input boundary edge).
  size_t on_fin = 0;
  for (const auto& [e, n] : edge_valences(m)) {
    const Eigen::Vector3d a = m.positions.row(e.first).transpose(), b = m.positions.row(e.second).transpose();
    const bool fin_edge = std::abs(a.y()) + std::abs(a.z()) + std::abs(b.y()) + std::abs(b.z()) < 1e-15;
    on_fin += fin_edge;
    if (fin_edge) EXPECT_EQ(n, 3) << a.transpose() << " - " << b.transpose();
    else EXPECT_LE(n, 2) << a.transpose() << " - " << b.transpose();
  }
  EXPECT_EQ(on_fin, st.non_manifold_splits + 1);  // each split of a fin edge makes one more
}

TEST(Refine, AVoxelCheckerboardKeepsRivarasBoundAtItsNonManifoldEdges) {
  // 14 cubes, every pair of diagonal neighbours sharing an edge of four faces, refined to ten
  // times its triangles where a step crosses the grid diagonally.
  Mesh m = test::build(test::checkerboard_voxels(3), 30.0);
  const size_t input_faces = m.num_faces();
  ASSERT_EQ(input_faces, 14u * 12u);
  const std::vector<double> input_angles = face_min_angles_deg(m);
  const double area = test::total_area(m);
  struct Diagonal : StepSignal {
    double at(const Eigen::Vector3d& p) const { return 1 / (1 + std::exp(-(p.x() + 0.7 * p.y() - 0.4 * p.z() - 1.9) / 0.05)); }
    void compute_values(const std::vector<NewVertex>& batch, const RowMatrixXd&, RowMatrixXd& values) override {
      for (size_t i = 0; i < batch.size(); ++i) values(static_cast<Eigen::Index>(i), 0) = at(batch[i].position);
    }
  } s;
  RowMatrixXd v(static_cast<Eigen::Index>(m.num_vertices()), 1);
  for (uint32_t i = 0; i < m.num_vertices(); ++i) v(i, 0) = s.at(m.point(i));
  const size_t input_nm = test::position_edges(m).non_manifold;
  EXPECT_EQ(input_nm, 36u);  // 3 axes x 12 edges where two cubes of the 3x3x3 checkerboard meet
  RefineStats st = refine_adaptive(m, v, s, RefineOptions{10 * input_faces, 16, 0});
  EXPECT_TRUE(st.warning.empty()) << st.warning;
  EXPECT_EQ(m.num_faces(), 10 * input_faces);
  EXPECT_EQ(st.non_manifold_edges, input_nm);
  EXPECT_GT(st.non_manifold_splits, 0u);
  EXPECT_NEAR(test::total_area(m), area, 1e-12 * area);
  expect_rivara_bound(input_angles, m);
  EXPECT_EQ(st.faces_below_1deg_after, 0u);
  // Conforming: every edge has two or four faces (no T-junction opens a boundary), and as many
  // four-face edges as splits of them added.
  size_t four = 0;
  for (const auto& [e, n] : edge_valences(m)) {
    EXPECT_TRUE(n == 2 || n == 4) << n;
    four += n == 4;
  }
  EXPECT_EQ(four, input_nm + st.non_manifold_splits);
  // Right isosceles triangles bisected on their hypotenuses stay right isosceles.
  EXPECT_NEAR(st.min_angle_after_deg, 45.0, 1e-9);
}

TEST(Refine, SliversDegenerateFacesAndAllCreaseTrianglesAreHandled) {
  // A sliver with a 0.001° angle next to a normal triangle, plus a zero-area face.
  RawMesh r;
  r.positions.resize(6, 3);
  const double h = std::tan(0.001 * M_PI / 180);
  r.positions << 0, 0, 0, 1, 0, 0, 1, h, 0, 0.5, -1, 0, 2, 0, 0, 3, 0, 0;
  r.face_indices = {0, 1, 2, 1, 0, 3, 1, 4, 5};  // the last one is collinear
  r.face_offsets = {0, 3, 6, 9};
  Mesh m = test::build(r);
  StepSignal s;
  s.x0 = 0.7;
  RowMatrixXd v = s.initial(m);
  const std::vector<double> input_angles = face_min_angles_deg(m);
  RefineStats st = refine_adaptive(m, v, s, RefineOptions{60, 4, 0});
  EXPECT_EQ(m.num_faces(), 60u);
  expect_rivara_bound(input_angles, m);  // neither the sliver nor the zero-area face seeds slivers
  EXPECT_EQ(st.faces_below_1deg_before, 2u);
  EXPECT_TRUE(v.allFinite());
  EXPECT_TRUE(m.normals.allFinite());
  EXPECT_GE(st.min_angle_after_deg, 0.5 * st.min_angle_before_deg);
  // A tetrahedron with every edge a crease.
  RawMesh tet;
  tet.positions.resize(4, 3);
  tet.positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  tet.face_indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  tet.face_offsets = {0, 3, 6, 9, 12};
  Mesh t = test::build(tet, 30.0);
  EXPECT_EQ(t.num_vertices(), 12u);
  RowMatrixXd tv = s.initial(t);
  refine_adaptive(t, tv, s, RefineOptions{40, 4, 0});
  EXPECT_EQ(t.num_faces(), 40u);
  EXPECT_EQ(test::position_edges(t).boundary, 0u);
}

TEST(Refine, SameInputSameOutput) {
  auto run = [](size_t batch) {
    Mesh m = test::build(test::icosphere(1));
    StepSignal s;
    RowMatrixXd v = s.initial(m);
    refine_adaptive(m, v, s, RefineOptions{500, batch, 0});
    return std::make_pair(m.triangles, v);
  };
  EXPECT_EQ(run(8), run(8));
}

TEST(Refine, MaxEdgePreRefinementBoundsEdgeLength) {
  Mesh m = test::build(test::grid(2));
  StepSignal s;
  RowMatrixXd v = s.initial(m);
  RefineStats st = refine_adaptive(m, v, s, RefineOptions{100000, 64, 0.2});
  EXPECT_GT(st.pre_refinement_splits, 0u);
  for (const Triangle& t : m.triangles)
    for (int k = 0; k < 3; ++k) EXPECT_LE((m.point(t[k]) - m.point(t[(k + 1) % 3])).norm(), 0.2 + 1e-12);
}

}  // namespace
}  // namespace prtsub

