// Procedural fixtures shared by the tests.
#pragma once

#include <string>

#include "prtsub/subdiv/mesh_io.h"

namespace prtsub::test {

//! A unit icosphere (radius 1 at the origin) subdivided `levels` times, as a RawMesh.
RawMesh icosphere(int levels);
//! An axis-aligned unit cube [0,1]^3 with outward winding, 12 triangles.
RawMesh cube();
//! The lower half of icosphere(levels), wound so its normals face the centre: a bowl open
//! upwards. From inside it a ray either leaves through the opening or hits the inside.
RawMesh bowl(int levels);
//! The unit cube wound inwards: a closed room, every ray from inside blocked.
RawMesh closed_room();
//! A square in the plane z = height spanning [-half, half]^2 (or [x0, half] in x), facing `up`.
RawMesh quad(double half, double height, bool facing_up, double x0 = NAN);
//! An n×n grid over [0,1]² at z = 0 facing +z, two triangles per cell (split along the diagonal
//! from (i, j) to (i+1, j+1)); interior points moved by up to ±jitter/2 cells (seeded), so that
//! areas differ as on real meshes.
RawMesh grid(int n, double jitter = 0, uint64_t seed = 3);
//! Unit cubes at the cells (i, j, k) of an n×n×n grid with i + j + k even (a 3D checkerboard),
//! 12 outward triangles each, corners shared: cubes that touch diagonally share an edge, which
//! then has four faces (a voxel world's non-manifold edges).
RawMesh checkerboard_voxels(int n);
//! The mesh's surface area, and its edge counts over positions (boundary, non-manifold, winding).
double total_area(const Mesh& m);
EdgeCounts position_edges(const Mesh& m);
//! Concatenates meshes (no welding).
RawMesh merge(const RawMesh& a, const RawMesh& b);
//! Applies p -> scale * p + offset.
RawMesh transformed(const RawMesh& m, double scale, const Eigen::Vector3d& offset);
//! The unit square as two triangles (0,0,0) (1,0,0) (1,1,0) and (0,0,0) (1,1,0) (0,1,0), as an
//! OBJ whose UVs are seamed along the diagonal: the first triangle maps by seam_uv(0, p) = (x, y),
//! the second by the affine seam_uv(1, p), so each diagonal corner has one UV per side.
std::string seam_square_obj();
Eigen::Vector2d seam_uv(int side, const Eigen::Vector3d& p);
//! Builds a Mesh with default options.
Mesh build(const RawMesh& m, double crease_angle = 60.0);

//! Writes an OBJ of the raw mesh (positions and faces; 17 significant digits).
void write_obj(const std::string& path, const RawMesh& m);

//! A fresh empty directory for one test, removed with its contents by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  std::string path(const std::string& name) const { return dir_ + "/" + name; }

 private:
  std::string dir_;
};

bool file_exists(const std::string& path);
void write_text(const std::string& path, const std::string& text);
//! Decodes standard base64 (fuzz findings are kept in the tests that way).
std::string base64_decode(const std::string& text);
//! Directory of ../shared/scenes, or "" when this clone has none.
std::string shared_scenes();

}  // namespace prtsub::test

namespace prtsub::test {
//! Gauss-Legendre nodes and weights on [-1, 1]; exact for polynomials of degree < 2n.
void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights);
//! A uniformly random rotation matrix from a seeded generator.
Eigen::Matrix3d random_rotation(uint64_t seed);
//! A uniformly random unit vector.
Eigen::Vector3d random_direction(uint64_t seed);
//! argmin over c ≥ 0 of cᵀGc − 2cᵀm (G symmetric positive definite, at most ~16 unknowns), by
//! solving on every support and keeping the best non-negative solution: an independent check of
//! non-negative encoders.
Eigen::VectorXd nnls_by_enumeration(const Eigen::MatrixXd& G, const Eigen::VectorXd& m);
}  // namespace prtsub::test
