// Seeded, area-stratified sample points on a mesh's surface: the data of the least-squares fit.
#pragma once

#include <cstdint>
#include <vector>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

struct SampleOptions {
  double per_triangle = 16;  //!< average samples per triangle (total = per_triangle · #F) ...
  double density = 0;        //!< ... or, when > 0, samples per unit area (total = density · area)
  size_t min_per_triangle = 1;  //!< every triangle of positive area gets at least this many
  uint64_t seed = 7;
};

//! Samples grouped by triangle: face f's samples are rows begin[f] .. begin[f+1]-1.
struct SurfaceSamples {
  //! #S by 3, on the surface (a simplified mesh's fit: on the source surface, where they are
  //! traced; `barycentric` then locates each at its closest point on the mesh)
  RowMatrixX3d points;
  RowMatrixX3d normals;      //!< #S by 3, interpolated render-vertex normals, unit
  RowMatrixX3d offsets;      //!< #S by 3, unit directions to move ray origins off the surface
  RowMatrixX3d barycentric;  //!< #S by 3, weights of the face's corners
  std::vector<uint32_t> face;   //!< #S
  std::vector<size_t> begin;    //!< #F + 1
  std::vector<double> weight;   //!< #S: the face's area over its sample count (Monte Carlo weight)
  //! #F, or empty: faces given no samples because interpolating the vertex values already
  //! reproduces the signal there (a pilot pass said so); the fit takes the prior's interpolant
  //! as their data instead of leaving them out
  std::vector<char> interpolated;
  size_t size() const { return face.size(); }
};

//! The point at barycentric weights `w` of face f, as every sample is placed: its position, the
//! corners' normals interpolated and normalised (the face's own normal where they cancel), and
//! the direction its rays leave the surface along (the face's normal, turned to the shading
//! side: inside a flat face it can never start a ray behind a neighbouring face).
struct SurfacePoint {
  Eigen::Vector3d point, normal, offset;
};
SurfacePoint surface_point(const Mesh& mesh, size_t face, const Eigen::Vector3d& w);

//! Each face of positive area gets min_per_triangle samples; the rest of the total is shared
//! in proportion to area by systematic sampling of the cumulative area (one seeded offset).
//! Within a face, n samples form a randomly shifted rank-1 lattice warped onto the triangle,
//! so each is uniform on the face (the estimate stays unbiased) and together they are stratified.
//! Zero-area faces get none. The result depends on the mesh and the seed only.
//! \throw InputError for a non-finite or negative count
SurfaceSamples make_surface_samples(const Mesh& mesh, const SampleOptions& options);

//! The same with a sample density per face: the samples beyond each face's minimum are shared
//! in proportion to area × face_weight[f] (finite, ≥ 0), and a face of weight 0 gets none at
//! all, not even the minimum, and is marked `interpolated`.
//! \throw InputError for a weight vector of the wrong size or a negative or non-finite weight
SurfaceSamples make_surface_samples(const Mesh& mesh, const SampleOptions& options, const std::vector<double>& face_weight);

//! Two sample sets on one mesh as one: face f's samples are a's then b's, each weighted by the
//! face's area over their total count, so a moment sum over the merged set is the count-weighted
//! mean of the two sets' estimates (each unbiased, so the merge is). `interpolated` is a's, or
//! b's when a has none; a face counts as interpolated only while neither set samples it.
//! \throw InputError when the two were made for different face counts
SurfaceSamples merge_surface_samples(const SurfaceSamples& a, const SurfaceSamples& b);

}  // namespace prtsub
