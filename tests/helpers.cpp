#include "helpers.h"

#include <Eigen/Dense>

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include "prtsub/subdiv/random.h"

namespace prtsub::test {

namespace {
void push_face(RawMesh& m, std::initializer_list<int64_t> idx) {
  if (m.face_offsets.empty()) m.face_offsets.push_back(0);
  for (int64_t i : idx) m.face_indices.push_back(i);
  m.face_offsets.push_back(m.face_indices.size());
}
}  // namespace

RawMesh icosphere(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size() - 1);
    };
    std::vector<std::array<int, 3>> g;
    for (auto& tri : f) {
      int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = g;
  }
  RawMesh m;
  m.positions.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) m.positions.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  for (auto& tri : f) push_face(m, {tri[0], tri[1], tri[2]});
  return m;
}

RawMesh bowl(int levels) {
  const RawMesh sphere = icosphere(levels);
  RawMesh m;
  m.positions = sphere.positions;
  m.face_offsets.push_back(0);
  for (size_t f = 0; f + 1 < sphere.face_offsets.size(); ++f) {
    const int64_t* c = &sphere.face_indices[sphere.face_offsets[f]];
    double z = 0;
    for (int k = 0; k < 3; ++k) z += sphere.positions(c[k], 2) / 3;
    if (z > 0.02) continue;
    m.face_indices.insert(m.face_indices.end(), {c[0], c[2], c[1]});  // reversed: facing inwards
    m.face_offsets.push_back(m.face_indices.size());
  }
  return m;
}

RawMesh closed_room() {
  RawMesh room = cube();
  for (size_t f = 0; f + 1 < room.face_offsets.size(); ++f) std::swap(room.face_indices[room.face_offsets[f] + 1], room.face_indices[room.face_offsets[f] + 2]);
  return room;
}

RawMesh cube() {
  RawMesh m;
  m.positions.resize(8, 3);
  for (int i = 0; i < 8; ++i) m.positions.row(i) << (i & 1), (i >> 1) & 1, (i >> 2) & 1;
  // Each quad (a, b, c, d) counter-clockwise seen from outside.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (auto& q : quads) {
    push_face(m, {q[0], q[1], q[2]});
    push_face(m, {q[0], q[2], q[3]});
  }
  return m;
}

RawMesh checkerboard_voxels(int n) {
  RawMesh m;
  const int g = n + 1;  // grid points per axis
  m.positions.resize(g * g * g, 3);
  for (int i = 0; i < g * g * g; ++i) m.positions.row(i) << i % g, (i / g) % g, i / (g * g);
  const RawMesh unit = cube();
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if ((i + j + k) % 2) continue;
        auto index = [&](int c) {  // the unit cube's corner c as a grid point
          return (i + (c & 1)) + g * (j + ((c >> 1) & 1)) + g * g * (k + ((c >> 2) & 1));
        };
        for (size_t f = 0; f + 1 < unit.face_offsets.size(); ++f)
          push_face(m, {index(int(unit.face_indices[unit.face_offsets[f]])), index(int(unit.face_indices[unit.face_offsets[f] + 1])),
                        index(int(unit.face_indices[unit.face_offsets[f] + 2]))});
      }
  return m;
}

RawMesh quad(double half, double height, bool facing_up, double x0) {
  RawMesh m;
  const double lo = std::isnan(x0) ? -half : x0;
  m.positions.resize(4, 3);
  m.positions << lo, -half, height, half, -half, height, half, half, height, lo, half, height;
  if (facing_up) {
    push_face(m, {0, 1, 2});
    push_face(m, {0, 2, 3});
  } else {
    push_face(m, {0, 2, 1});
    push_face(m, {0, 3, 2});
  }
  return m;
}

RawMesh grid(int n, double jitter, uint64_t seed) {
  RawMesh m;
  m.positions.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      double x = double(i) / n, y = double(j) / n;
      if (jitter > 0 && i > 0 && i < n && j > 0 && j < n) {
        Rng r(seed, uint64_t(j * (n + 1) + i));
        x += jitter / n * (r.uniform() - 0.5), y += jitter / n * (r.uniform() - 0.5);
      }
      m.positions.row(j * (n + 1) + i) << x, y, 0;
    }
  m.face_offsets.push_back(0);
  auto face = [&](int64_t a, int64_t b, int64_t c) {
    m.face_indices.insert(m.face_indices.end(), {a, b, c});
    m.face_offsets.push_back(m.face_indices.size());
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int64_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      face(a, b, c), face(a, c, d);
    }
  return m;
}

double total_area(const Mesh& m) {
  double a = 0;
  for (const Triangle& t : m.triangles) a += triangle_area(m.point(t[0]), m.point(t[1]), m.point(t[2]));
  return a;
}

EdgeCounts position_edges(const Mesh& m) {
  std::vector<Triangle> t(m.triangles.size());
  for (size_t f = 0; f < t.size(); ++f)
    for (int k = 0; k < 3; ++k) t[f][k] = m.vertex_position[m.triangles[f][k]];
  return count_edges(t);
}

RawMesh merge(const RawMesh& a, const RawMesh& b) {
  RawMesh m = a;
  const int64_t shift = a.positions.rows();
  m.positions.resize(a.positions.rows() + b.positions.rows(), 3);
  m.positions << a.positions, b.positions;
  if (m.face_offsets.empty()) m.face_offsets.push_back(0);
  for (size_t f = 0; f + 1 < b.face_offsets.size(); ++f) {
    for (size_t c = b.face_offsets[f]; c < b.face_offsets[f + 1]; ++c) m.face_indices.push_back(b.face_indices[c] + shift);
    m.face_offsets.push_back(m.face_indices.size());
  }
  if (a.colors.rows() > 0 || b.colors.rows() > 0) {  // a part without colours is white
    m.colors.setOnes(m.positions.rows(), 3);
    if (a.colors.rows() > 0) m.colors.topRows(a.colors.rows()) = a.colors;
    if (b.colors.rows() > 0) m.colors.bottomRows(b.colors.rows()) = b.colors;
    m.colors_linear = a.colors.rows() > 0 ? a.colors_linear : b.colors_linear;
  }
  return m;
}

RawMesh transformed(const RawMesh& m, double scale, const Eigen::Vector3d& offset) {
  RawMesh out = m;
  for (Eigen::Index i = 0; i < out.positions.rows(); ++i)
    out.positions.row(i) = (scale * m.positions.row(i).transpose() + offset).transpose();
  return out;
}

std::string seam_square_obj() {
  return "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
         "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\nvt 0.7 0.7\n"
         "f 1/1 2/2 3/3\nf 1/5 3/6 4/4\n";
}

Eigen::Vector2d seam_uv(int side, const Eigen::Vector3d& p) {
  if (side == 0) return {p.x(), p.y()};
  // Through (0,0) -> (0.5,0.5), (1,1) -> (0.7,0.7), (0,1) -> (0,1).
  return {0.5 + 0.7 * p.x() - 0.5 * p.y(), 0.5 - 0.3 * p.x() + 0.5 * p.y()};
}

Mesh build(const RawMesh& m, double crease_angle) { return build_mesh(m, "test", LoadOptions{crease_angle}); }

void write_obj(const std::string& path, const RawMesh& m) {
  std::ofstream out(path);
  out.precision(17);
  for (Eigen::Index i = 0; i < m.positions.rows(); ++i)
    out << "v " << m.positions(i, 0) << " " << m.positions(i, 1) << " " << m.positions(i, 2) << "\n";
  for (size_t f = 0; f + 1 < m.face_offsets.size(); ++f) {
    out << "f";
    for (size_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) out << " " << m.face_indices[c] + 1;
    out << "\n";
  }
}

TempDir::TempDir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "prtsub_test_XXXXXX").string();
  if (!::mkdtemp(tmpl.data())) std::abort();
  dir_ = tmpl;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

bool file_exists(const std::string& path) { return std::filesystem::exists(path); }

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string base64_decode(const std::string& text) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
  };
  std::string out;
  uint32_t bits = 0;
  int count = 0;
  for (char c : text) {
    const int v = value(c);
    if (v < 0) continue;  // padding
    bits = (bits << 6) | uint32_t(v);
    if ((count += 6) >= 8) out += static_cast<char>((bits >> (count -= 8)) & 0xFF);
  }
  return out;
}

std::string shared_scenes() {
  std::string dir = PRTSUB_SHARED_SCENES;
  return std::filesystem::is_directory(dir) ? dir : "";
}


void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
  nodes.resize(static_cast<size_t>(n));
  weights.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = x;
      for (int k = 2; k <= n; ++k) {
        double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (x * p1 - p0) / (x * x - 1);
      double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    nodes[static_cast<size_t>(i)] = x;
    weights[static_cast<size_t>(i)] = 2 / ((1 - x * x) * dp * dp);
  }
}

Eigen::Vector3d random_direction(uint64_t seed) {
  Rng rng(seed, 7);
  double z = 2 * rng.uniform() - 1, phi = 2 * M_PI * rng.uniform(), r = std::sqrt(1 - z * z);
  return {r * std::cos(phi), r * std::sin(phi), z};
}

Eigen::Matrix3d random_rotation(uint64_t seed) {
  Rng rng(seed, 11);
  Eigen::Quaterniond q(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
  return q.normalized().toRotationMatrix();
}

}  // namespace prtsub::test

namespace prtsub::test {

Eigen::VectorXd nnls_by_enumeration(const Eigen::MatrixXd& G, const Eigen::VectorXd& m) {
  const int N = int(m.size());
  Eigen::VectorXd best = Eigen::VectorXd::Zero(N);
  double best_value = 0;
  for (int mask = 1; mask < (1 << N); ++mask) {
    std::vector<int> idx;
    for (int i = 0; i < N; ++i)
      if (mask >> i & 1) idx.push_back(i);
    const auto n = Eigen::Index(idx.size());
    Eigen::MatrixXd g(n, n);
    Eigen::VectorXd r(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      r[i] = m[idx[size_t(i)]];
      for (Eigen::Index j = 0; j < n; ++j) g(i, j) = G(idx[size_t(i)], idx[size_t(j)]);
    }
    const Eigen::VectorXd x = g.ldlt().solve(r);
    if (x.minCoeff() < 0) continue;
    Eigen::VectorXd c = Eigen::VectorXd::Zero(N);
    for (Eigen::Index i = 0; i < n; ++i) c[idx[size_t(i)]] = x[i];
    const double value = c.dot(G * c) - 2 * c.dot(m);
    if (value < best_value) best_value = value, best = c;
  }
  return best;
}

}  // namespace prtsub::test
