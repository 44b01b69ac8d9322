// The nearest point of a mesh's surface to each of many points (Embree's point queries): how a
// simplified asset is located from points of the surface it was simplified from.
#pragma once

#include <vector>

#include "prtsub/prt/ray_scene.h"
#include "prtsub/subdiv/mesh.h"

namespace prtsub {

struct SurfaceLocation {
  uint32_t face = 0;                       //!< a face of the mesh
  Eigen::Vector3d barycentric{1, 0, 0};  //!< weights of its corners, each in [0, 1], summing to 1
  double distance = 0;                     //!< from the query point
};

//! For each row of `points`, the closest point on the mesh's faces (ties: the lower face).
//! With `normals` (one per point), the closest among the faces whose winding faces the point's
//! normal's way (a positive dot), so that a point on one side of a thin wall or a table top is
//! not located on the other; any face where none does. The result does not depend on `threads`
//! (0: every core).
//! \throw InputError for a mesh without faces, a non-finite point or a normal count that does not
//!        match; EmbreeError if Embree fails
std::vector<SurfaceLocation> closest_points(const Mesh& mesh, const RowMatrixX3d& points, int threads = 0,
                                            const RowMatrixX3d* normals = nullptr);
//! The same with the mesh's scene built by the caller, once for several calls (points located in
//! chunks): `scene` must be RayScene(mesh.positions, position_triangles(mesh)).
std::vector<SurfaceLocation> closest_points(const Mesh& mesh, const RayScene& scene, const RowMatrixX3d& points, int threads = 0,
                                            const RowMatrixX3d* normals = nullptr);

//! The closest point of triangle (a, b, c) to p, as barycentric weights of a, b, c.
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c);

}  // namespace prtsub
