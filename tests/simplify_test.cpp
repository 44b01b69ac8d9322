#include "prtsub/subdiv/simplify.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>

#include "helpers.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/refine.h"

namespace prtsub {
namespace {

// One value per render vertex: a function of its position.
template <class F>
RowMatrixXd values_of(const Mesh& m, F&& f, int K = 1) {
  RowMatrixXd v(static_cast<Eigen::Index>(m.num_vertices()), K);
  for (uint32_t i = 0; i < m.num_vertices(); ++i)
    for (int k = 0; k < K; ++k) v(i, k) = f(m.point(i)) * (k + 1);
  return v;
}

// A unit cube with each side an n×n grid (welded by the loader), every cube edge a crease.
RawMesh tessellated_cube(int n) {
  RawMesh m;
  std::vector<Eigen::Vector3d> pts;
  m.face_offsets.push_back(0);
  // Each side: origin, two spanning axes (their cross product points out).
  const Eigen::Vector3d o[6] = {{0, 0, 0}, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}};
  const Eigen::Vector3d u[6] = {{0, 1, 0}, {1, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 0, 1}, {0, 1, 0}};
  const Eigen::Vector3d w[6] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int s = 0; s < 6; ++s) {
    const int64_t base = static_cast<int64_t>(pts.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) pts.push_back(o[s] + u[s] * double(i) / n + w[s] * double(j) / n);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int64_t a = base + j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
        m.face_indices.insert(m.face_indices.end(), {a, b, c, a, c, d});
        m.face_offsets.push_back(m.face_indices.size() - 3);
        m.face_offsets.push_back(m.face_indices.size());
      }
  }
  m.positions.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) m.positions.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  return m;
}

TEST(Simplify, ReachesTheBudgetExactlyAndKeepsSurvivingVerticesAsTheyWere) {
  // Open: exact for any budget (a boundary collapse removes one face).
  for (size_t budget : {201u, 200u, 57u}) {
    Mesh m = test::build(test::grid(20, 0.3));
    const Mesh in = m;
    RowMatrixXd v = values_of(m, [](const Eigen::Vector3d& p) { return std::sin(6 * p.x()) + p.y(); }, 3);
    const RowMatrixXd v_in = v;
    std::vector<uint32_t> to;
    size_t told = 0;
    SimplifyStats st = simplify(m, v, SimplifyOptions{budget}, &to, [&](size_t n) { told += n; });
    EXPECT_TRUE(st.warning.empty()) << st.warning;
    EXPECT_EQ(told, st.collapses);  // the progress bar is told of every collapse, the last one too
    EXPECT_EQ(m.num_faces(), budget);
    EXPECT_EQ(st.faces_after, budget);
    ASSERT_EQ(v.rows(), static_cast<Eigen::Index>(m.num_vertices()));
    EXPECT_TRUE(st.moved.empty());  // no creases, so no corner's render vertex moved
    for (uint32_t i = 0; i < in.num_vertices(); ++i) {
      if (to[i] == UINT32_MAX) continue;
      EXPECT_EQ(m.point(to[i]), in.point(i));  // half-edge collapses move nothing
      EXPECT_EQ(v.row(to[i]), v_in.row(i));
    }
    for (uint32_t s : m.source_face) EXPECT_LT(s, in.num_faces());
    EXPECT_NEAR(test::total_area(m), 1.0, 1e-12);  // flat and its outline kept: the area cannot change
  }
  // Closed: even counts only, so an odd budget ends one below with a warning.
  Mesh s = test::build(test::icosphere(3));
  RowMatrixXd v = values_of(s, [](const Eigen::Vector3d& p) { return p.z(); });
  SimplifyStats st = simplify(s, v, SimplifyOptions{301});
  EXPECT_EQ(s.num_faces(), 300u);
  EXPECT_FALSE(st.warning.empty());
  // Not below the input: nothing happens.
  Mesh g = test::build(test::grid(4));
  RowMatrixXd gv = values_of(g, [](const Eigen::Vector3d& p) { return p.x(); });
  EXPECT_FALSE(simplify(g, gv, SimplifyOptions{32}).warning.empty());
  EXPECT_EQ(g.num_faces(), 32u);
}

TEST(Simplify, GuardsNoFlipsManifoldMinimumAngleBoundariesAndCreases) {
  // A closed sphere at a tenth of its faces: still closed, manifold, every face facing out.
  Mesh s = test::build(test::icosphere(3));
  RowMatrixXd v = values_of(s, [](const Eigen::Vector3d& p) { return p.x() > 0.2 ? 1.0 : 0.0; });
  SimplifyOptions o{128};
  o.min_angle_deg = 15;
  SimplifyStats st = simplify(s, v, o);
  EXPECT_EQ(s.num_faces(), 128u);
  EdgeCounts e = test::position_edges(s);
  EXPECT_EQ(e.boundary, 0u);
  EXPECT_EQ(e.non_manifold, 0u);
  EXPECT_EQ(e.winding_conflicts, 0u);
  EXPECT_EQ(static_cast<long>(s.positions.rows()) - static_cast<long>(e.edges) + static_cast<long>(s.num_faces()), 2);
  for (const Triangle& t : s.triangles) {
    const Eigen::Vector3d a = s.point(t[0]), b = s.point(t[1]), c = s.point(t[2]);
    EXPECT_GT((b - a).cross(c - a).dot(a + b + c), 0) << "a face turned inwards";
  }
  EXPECT_GE(st.min_angle_after_deg, 15.0);  // the input's smallest is above it, so every face is
  EXPECT_EQ(st.faces_below_min_angle, 0u);
  // A cube of 6 x 2 x 8 x 8 triangles: its corners are kept by the line and surface tolerances
  // (or locked, when corners may not collapse), its edges (creases) stay straight and keep one
  // render vertex per side, so the cube keeps its exact shape.
  for (bool corners : {true, false}) {
  Mesh c = test::build(tessellated_cube(8), 30.0);
  ASSERT_EQ(c.num_faces(), 768u);
  RowMatrixXd cv = values_of(c, [](const Eigen::Vector3d& p) { return p.x() * p.y() + p.z(); });
  SimplifyOptions co{60};
  co.collapse_corners = corners;
  st = simplify(c, cv, co);
  EXPECT_EQ(c.num_faces(), 60u) << st.warning;
  EXPECT_EQ(st.locked_vertices, corners ? 0u : 8u);
  EXPECT_EQ(st.corner_collapses, 0u);
  EXPECT_NEAR(test::total_area(c), 6.0, 1e-12);
  EXPECT_EQ(test::position_edges(c).boundary, 0u);
  for (Eigen::Index p = 0; p < c.positions.rows(); ++p) {  // every position on the cube's surface
    const Eigen::Vector3d q = c.positions.row(p).transpose();
    EXPECT_NEAR(std::min(q.minCoeff(), 1 - q.maxCoeff()), 0.0, 1e-15);
  }
  for (uint32_t i = 0; i < c.num_vertices(); ++i) {  // normals still those of one side each
    const Eigen::Vector3d n = c.normals.row(i).transpose();
    EXPECT_NEAR(n.cwiseAbs().maxCoeff(), 1.0, 1e-12);
  }
  std::set<uint32_t> cube_corners;
  for (uint32_t i = 0; i < c.num_vertices(); ++i) {
    const Eigen::Vector3d q = c.point(i);
    if ((q.array() == 0 || q.array() == 1).all()) cube_corners.insert(c.vertex_position[i]);
  }
  EXPECT_EQ(cube_corners.size(), 8u);
  }
}

// A flat n×n grid in three UV charts: x < 1/2, and x > 1/2 split at y = 1/2. The seams meet at
// (1/2, 1/2) in a T: a crease corner, with one render vertex per chart. Its render vertex of
// the chart the collapse does not slide along moves to the kept position.
Mesh three_charts(int n) {
  const Mesh g = test::build(test::grid(n));
  Mesh m = g;
  auto chart = [&](const Triangle& t) {
    const Eigen::Vector3d c = (g.point(t[0]) + g.point(t[1]) + g.point(t[2])) / 3;
    return c.x() < 0.5 ? 0 : c.y() < 0.5 ? 1 : 2;
  };
  std::map<std::pair<uint32_t, int>, uint32_t> render;
  m.vertex_position.clear();
  std::vector<Eigen::Vector2d> uv;
  for (Triangle& t : m.triangles) {
    const int c = chart(t);
    for (uint32_t& v : t) {
      const uint32_t p = g.vertex_position[v];
      auto [it, fresh] = render.try_emplace({p, c}, uint32_t(m.vertex_position.size()));
      if (fresh) m.vertex_position.push_back(p), uv.push_back({g.positions(p, 0) + 2 * c, g.positions(p, 1)});
      v = it->second;
    }
  }
  m.normals = RowMatrixX3d(Eigen::Index(uv.size()), 3);
  m.uv = RowMatrixX2d(Eigen::Index(uv.size()), 2);
  for (size_t i = 0; i < uv.size(); ++i) {
    m.normals.row(Eigen::Index(i)) = Eigen::RowVector3d(0, 0, 1);
    m.uv.row(Eigen::Index(i)) = uv[i].transpose();
  }
  return m;
}

TEST(Simplify, ACreaseCornerCollapsesAlongOneCreaseAndItsOtherSideMovesWithIt) {
  // Tolerances loose enough for the T's stem to give way (a real mesh's corner moves only where
  // its creases stay within them: ScenesSimplify.MoriKnobAtATenth... counts its corner collapses).
  for (bool corners : {true, false}) {
    Mesh m = three_charts(8);
    const Mesh in = m;
    RowMatrixXd v = values_of(m, [](const Eigen::Vector3d& p) { return p.x() + 2 * p.y(); });
    SimplifyOptions o{4};
    o.feature_tolerance = 0.3, o.min_angle_deg = 0, o.collapse_corners = corners;
    std::vector<uint32_t> to;
    const SimplifyStats st = simplify(m, v, o, &to);
    bool centre = false;
    for (Eigen::Index p = 0; p < m.positions.rows(); ++p) centre |= m.positions.row(p) == Eigen::RowVector3d(0.5, 0.5, 0);
    if (!corners) {  // the T's corner is locked, with the seams' three ends on the boundary
      EXPECT_TRUE(centre);
      EXPECT_EQ(st.locked_vertices, 4u);
      EXPECT_TRUE(st.moved.empty());
      continue;
    }
    EXPECT_EQ(m.num_faces(), 4u) << st.warning;
    EXPECT_FALSE(centre);  // the corner itself collapsed
    EXPECT_EQ(st.locked_vertices, 3u);
    EXPECT_GE(st.corner_collapses, 1u);
    ASSERT_FALSE(st.moved.empty());
    // Each face stays in one chart (the UVs' offset tells them apart), on the plane, facing up,
    // and the faces tile their outline (the loose tolerance let the square's corners go): a
    // manifold disk whose faces' areas sum to the area its boundary encloses.
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (const Triangle& t : m.triangles) {
      EXPECT_EQ(std::floor(m.uv(t[0], 0) / 2), std::floor(m.uv(t[1], 0) / 2));
      EXPECT_EQ(std::floor(m.uv(t[0], 0) / 2), std::floor(m.uv(t[2], 0) / 2));
      EXPECT_GT((m.point(t[1]) - m.point(t[0])).cross(m.point(t[2]) - m.point(t[0])).z(), 0);
      for (int k = 0; k < 3; ++k) ++directed[{m.vertex_position[t[k]], m.vertex_position[t[(k + 1) % 3]]}];
    }
    const EdgeCounts e = test::position_edges(m);
    EXPECT_EQ(e.non_manifold + e.winding_conflicts, 0u);
    EXPECT_EQ(long(m.positions.rows()) - long(e.edges) + long(m.num_faces()), 1);
    double enclosed = 0;
    for (const auto& [ab, n] : directed) {
      if (directed.count({ab.second, ab.first})) continue;  // inner edge
      const Eigen::RowVector3d a = m.positions.row(ab.first), b = m.positions.row(ab.second);
      enclosed += 0.5 * (a.x() * b.y() - b.x() * a.y());
    }
    EXPECT_NEAR(test::total_area(m), enclosed, 1e-12);
    // A moved render vertex keeps its chart's UVs, now stands where another input vertex stood
    // (on the input surface, where the caller can trace it again), and its value is its faces'
    // extended there: the linear signal's value at its new place.
    std::set<uint32_t> moved(st.moved.begin(), st.moved.end());
    size_t kept_in_place = 0;
    for (uint32_t i = 0; i < in.num_vertices(); ++i) {
      if (to[i] == UINT32_MAX) continue;
      EXPECT_EQ(m.uv.row(to[i]), in.uv.row(i));
      EXPECT_NEAR(v(to[i], 0), m.point(to[i]).x() + 2 * m.point(to[i]).y(), 1e-12);
      if (!moved.count(to[i])) {
        EXPECT_EQ(m.point(to[i]), in.point(i));
        ++kept_in_place;
        continue;
      }
      EXPECT_NE(m.point(to[i]), in.point(i));
      bool an_input_position = false;
      for (Eigen::Index p = 0; p < in.positions.rows(); ++p) an_input_position |= in.positions.row(p) == m.point(to[i]).transpose();
      EXPECT_TRUE(an_input_position);
    }
    EXPECT_EQ(kept_in_place + moved.size(), m.num_vertices());
  }
}

// Whether face f of m points against one of its corners' render normals.
bool faces_against_its_normals(const Mesh& m, size_t f) {
  const Triangle& t = m.triangles[f];
  const Eigen::Vector3d n = (m.point(t[1]) - m.point(t[0])).cross(m.point(t[2]) - m.point(t[0]));
  bool against = false;
  for (uint32_t r : t) against |= !(n.dot(m.normals.row(r).transpose()) > 0);
  return against;
}

TEST(Simplify, NoFaceComesToFaceAgainstItsCornersNormals) {
  // A flat grid whose corner render vertex at the origin has a normal pointing down (as a vertex
  // across a sharp fold would): the faces there face against it. The corner stays (the boundary's
  // shape), so a collapse into it would give a face that faced no normal wrongly a corner whose
  // normal it faces against. No output face does, unless the input face it descends from did.
  for (size_t budget : {60u, 20u, 8u}) {
    Mesh m = test::build(test::grid(8));
    const Mesh in = m;
    uint32_t corner = UINT32_MAX;
    for (uint32_t i = 0; i < m.num_vertices(); ++i)
      if (m.point(i) == Eigen::Vector3d(0, 0, 0)) corner = i;
    ASSERT_NE(corner, UINT32_MAX);
    m.normals.row(corner) = Eigen::RowVector3d(0, 0, -1);
    const Mesh marked = m;
    RowMatrixXd v = values_of(m, [](const Eigen::Vector3d& p) { return p.x() * p.y(); });
    SimplifyOptions o{budget};
    o.min_angle_deg = 0;
    const SimplifyStats st = simplify(m, v, o);
    EXPECT_LE(m.num_faces(), budget) << st.warning;
    EXPECT_GE(m.num_faces() + 1, budget) << st.warning;  // a boundary collapse the guards allow may be missing
    bool kept = false;
    for (uint32_t i = 0; i < m.num_vertices(); ++i) kept |= m.point(i) == Eigen::Vector3d(0, 0, 0);
    EXPECT_TRUE(kept);
    size_t against = 0;
    for (size_t f = 0; f < m.num_faces(); ++f)
      if (faces_against_its_normals(m, f)) {
        ++against;
        EXPECT_TRUE(faces_against_its_normals(marked, m.source_face[f])) << "budget " << budget << ", face " << f;
      }
    EXPECT_GE(against, 1u);  // the corner's own fan
  }
}

TEST(Simplify, TheTransferMetricKeepsVerticesWhereTheSignalChanges) {
  // A flat grid with a sharp shadow edge: the quadric sees nothing to choose between, the signal
  // metric keeps the vertices that carry the edge. Error: RMS of the output's interpolant
  // against the signal at points on a fine lattice, located by brute force.
  auto signal = [](const Eigen::Vector3d& p) { return 1 / (1 + std::exp(-(p.x() + 0.3 * p.y() - 0.6) / 0.03)); };
  auto rms = [&](SimplifyMetric metric) {
    Mesh m = test::build(test::grid(40));
    RowMatrixXd v = values_of(m, signal);
    SimplifyOptions o{400};
    o.metric = metric;
    simplify(m, v, o);
    EXPECT_EQ(m.num_faces(), 400u);
    double sum = 0;
    int n = 0;
    for (int j = 0; j < 60; ++j)
      for (int i = 0; i < 60; ++i) {
        const Eigen::Vector3d p((i + 0.5) / 60, (j + 0.5) / 60, 0);
        for (const Triangle& t : m.triangles) {
          const Eigen::Vector3d a = m.point(t[0]), b = m.point(t[1]), c = m.point(t[2]);
          const double area = (b - a).cross(c - a).z();
          const double l0 = (b - p).cross(c - p).z() / area, l1 = (c - p).cross(a - p).z() / area, l2 = 1 - l0 - l1;
          if (l0 < -1e-12 || l1 < -1e-12 || l2 < -1e-12) continue;
          const double f = l0 * v(t[0], 0) + l1 * v(t[1], 0) + l2 * v(t[2], 0);
          sum += std::pow(f - signal(p), 2), ++n;
          break;
        }
      }
    EXPECT_EQ(n, 3600);
    return std::sqrt(sum / n);
  };
  const double transfer = rms(SimplifyMetric::Transfer), geometry = rms(SimplifyMetric::Geometry);
  EXPECT_LT(transfer, 0.1 * geometry) << transfer << " against " << geometry;
}

TEST(Simplify, NoisyValuesAreRankedNetOfTheirNoise) {
  // A flat grid whose left half carries a linear signal plus noise of known variance and whose
  // right half a noise-free ripple. Ranked on the raw values, the noise looks like signal and
  // the left half keeps vertices for it; told the variance, the collapses there cost what the
  // (linear) signal loses, nothing, and the vertices go to the ripple. Error: RMS of the
  // output's interpolant against the noise-free signal on the right half, at a fine lattice.
  const double sigma = 0.05;
  auto truth = [](const Eigen::Vector3d& p) {
    return p.x() < 0.5 ? 0.2 + 0.1 * p.x() : 0.25 + 0.05 * std::sin(4 * M_PI * p.y()) * std::sin(2 * M_PI * (p.x() - 0.5));
  };
  struct Result {
    size_t right = 0;  // surviving vertices with x > 0.5
    double rms = 0;
  };
  auto run = [&](bool told) {
    Mesh m = test::build(test::grid(40));
    RowMatrixXd v = values_of(m, truth);
    std::vector<double> variance(m.num_vertices(), 0.0);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0, sigma);
    for (uint32_t i = 0; i < m.num_vertices(); ++i)
      if (m.point(i).x() < 0.5 - 1e-9) v(i, 0) += noise(rng), variance[i] = sigma * sigma;
    SimplifyOptions o{600};
    o.geometry_weight = 0;  // flat: only the signal ranks
    simplify(m, v, o, nullptr, {}, told ? &variance : nullptr);
    EXPECT_EQ(m.num_faces(), 600u);
    Result r;
    for (uint32_t i = 0; i < m.num_vertices(); ++i) r.right += m.point(i).x() > 0.5 + 1e-9;
    double sum = 0;
    int n = 0;
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 20; ++i) {
        const Eigen::Vector3d p(0.5 + (i + 0.5) / 40, (j + 0.5) / 40, 0);
        for (const Triangle& t : m.triangles) {
          const Eigen::Vector3d a = m.point(t[0]), b = m.point(t[1]), c = m.point(t[2]);
          const double area = (b - a).cross(c - a).z();
          const double l0 = (b - p).cross(c - p).z() / area, l1 = (c - p).cross(a - p).z() / area, l2 = 1 - l0 - l1;
          if (l0 < -1e-12 || l1 < -1e-12 || l2 < -1e-12) continue;
          sum += std::pow(l0 * v(t[0], 0) + l1 * v(t[1], 0) + l2 * v(t[2], 0) - truth(p), 2), ++n;
          break;
        }
      }
    EXPECT_EQ(n, 800);
    r.rms = std::sqrt(sum / n);
    return r;
  };
  const Result raw = run(false), net = run(true);
  // Measured: 190 against 12 vertices on the right, RMS 0.0031 against 0.0065.
  EXPECT_GT(net.right, 4 * raw.right) << net.right << " against " << raw.right;
  EXPECT_LT(net.rms, 0.6 * raw.rms) << net.rms << " against " << raw.rms;
}

TEST(Simplify, UnknownOrZeroVariancesRankAsNoVariance) {
  // NaN (a value whose noise is not known: spherical-Gaussian lobes) and 0 (exact) subtract
  // nothing: the same collapses, to the bit, as without a variance.
  auto run = [](const std::vector<double>* variance) {
    Mesh m = test::build(test::grid(20, 0.3));
    RowMatrixXd v = values_of(m, [](const Eigen::Vector3d& p) { return std::sin(6 * p.x()) + p.y(); }, 2);
    std::vector<double> sized;
    if (variance) sized.assign(m.num_vertices(), (*variance)[0]);
    simplify(m, v, SimplifyOptions{150}, nullptr, {}, variance ? &sized : nullptr);
    return std::make_pair(m, v);
  };
  const auto [m0, v0] = run(nullptr);
  for (double x : {std::nan(""), 0.0}) {
    const std::vector<double> one{x};
    const auto [m1, v1] = run(&one);
    EXPECT_EQ(m1.triangles, m0.triangles) << x;
    EXPECT_EQ(v1, v0) << x;
  }
  // A variance that is known does change the ranking (else the cases above prove nothing).
  const std::vector<double> known{0.05};
  EXPECT_NE(run(&known).first.triangles, m0.triangles);
}

TEST(Simplify, FacesOpenMeshCannotTakeAreKeptAsTheyAre) {
  // A grid with a fin on one of its interior edges: three faces on that edge.
  RawMesh r = test::grid(10);
  const int64_t a = 5 * 11 + 5, c = a + 12;  // the diagonal (5,5)-(6,6)
  const int64_t top = r.positions.rows();
  r.positions.conservativeResize(top + 1, 3);
  r.positions.row(top) << 0.55, 0.55, 0.3;
  r.face_indices.insert(r.face_indices.end(), {a, c, top});
  r.face_offsets.push_back(r.face_indices.size());
  Mesh m = test::build(r);
  ASSERT_EQ(test::position_edges(m).non_manifold, 1u);
  RowMatrixXd v = values_of(m, [](const Eigen::Vector3d& p) { return p.x(); });
  SimplifyStats st = simplify(m, v, SimplifyOptions{50});
  EXPECT_EQ(st.kept_faces, 1u);
  EXPECT_EQ(m.num_faces(), 50u);
  EXPECT_TRUE(v.allFinite());
  bool fin = false;
  for (const Triangle& t : m.triangles)
    for (uint32_t i : t) fin |= m.point(i).z() > 0.2;
  EXPECT_TRUE(fin);
  // Bad options are refused.
  SimplifyOptions bad{10};
  bad.min_angle_deg = 70;
  EXPECT_THROW(simplify(m, v, bad), InputError);
  RowMatrixXd wrong(3, 1);
  EXPECT_THROW(simplify(m, wrong, SimplifyOptions{10}), InputError);
  const std::vector<double> short_variance(m.num_vertices() - 1, 0.0);
  EXPECT_THROW(simplify(m, v, SimplifyOptions{10}, nullptr, {}, &short_variance), InputError);
}

}  // namespace
}  // namespace prtsub
