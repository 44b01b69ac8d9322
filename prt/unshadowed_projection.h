// The unshadowed part of shadowed transfer, known in closed form, projected exactly onto the
// mesh's piecewise-linear functions: what no ray needs to be traced for.
#pragma once

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

struct UnshadowedProjectionOptions {
  double tolerance =
      1e-8;  //!< CG's relative residual per column (the scaled mass matrix converges in ~15 passes)
  int threads = 0;  //!< 0: every core; the result does not depend on it
};

struct UnshadowedProjectionStats {
  int iterations = 0;            //!< CG passes over the mass matrix
  size_t quadrature_points = 0;  //!< points at which t_u was integrated, over all faces
  size_t fixed_vertices = 0;     //!< vertices with no face of positive area: kept at t_u(n_i)
  double seconds = 0;
};

//! t_u(n) = Â_l·y_lm(n) at each unit normal: #N by order².
RowMatrixXd unshadowed_at(const RowMatrixX3d& normals, int order);

//! Each vertex's open share w_i = t_i,0 / t_u,0 in [0, 1]: its DC coefficient against an open
//! point's (1 where nothing is blocked, 0 where everything is). t_u's curvature in n shows in t
//! as far as the point is open, so w·t_u is the known part of the signal (docs/fit.md).
//! \param values #V by at least 1 column: shadowed transfer (its first column, the DC term, is
//! read)
std::vector<double> open_share(const RowMatrixXd& values);

//! The L2 projection of w(p)·t_u(n(p)) onto the mesh's piecewise-linear functions: x minimising
//! ∫ ‖Σ_i h_i(p) x_i − w(p)·t_u(n(p))‖² dA over the surface, with n(p) the normalised
//! interpolation of the face's corner normals (as samples and eval's reference take it; the face's
//! own normal where that vanishes) and w(p) the linear interpolation of the vertices' weights (1
//! everywhere without `weight`). Each side of a crease has its own render vertices, so the
//! projection may jump there as the normals do. Linear interpolation of t_u(n_i) misses t_u's
//! curvature in n inside every face (about 1% of ‖t_u‖ on a dense scan); this is the best any
//! vertex values can do for that part, found with no rays and no noise.
//! \param weight #V, or null for 1
//! \return #V by order²; a vertex with no face of positive area keeps w_i·t_u(n_i)
//! \throw InputError for an order outside 1..10, a mesh without normals or a weight of the wrong
//! size
RowMatrixXd unshadowed_projection(const Mesh& mesh, int order,
                                  const UnshadowedProjectionOptions& options = {},
                                  UnshadowedProjectionStats* stats = nullptr,
                                  const std::vector<double>* weight = nullptr);

}  // namespace prtsub
