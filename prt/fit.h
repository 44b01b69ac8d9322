// Vertex values from surface samples: point sampling's alternatives (Kavan, Bargteil, Sloan
// 2011). The fit sees only the mesh, the samples and their values, so it is testable without rays.
#pragma once

#include <Eigen/SparseCore>
#include <memory>
#include <string>

#include "prtsub/prt/block_cg.h"
#include "prtsub/prt/surface_samples.h"

namespace prtsub {

using SparseMatrixd = Eigen::SparseMatrix<double>;

enum class FitMethod { Point, Average, LeastSquares };
enum class Regularizer { Edge, Gradient };
enum class MassMatrix { Analytic, Sampled };
//! Auto: conjugate gradients with the analytic mass matrix, falling back to CHOLMOD if they do
//! not converge; CHOLMOD's Cholesky factorisation for the sampled one. Cholmod: always CHOLMOD.
enum class FitSolver { Auto, Cholmod };

FitMethod parse_fit_method(const std::string& name);        //!< point, average, lsq
Regularizer parse_regularizer(const std::string& name);     //!< edge, gradient
MassMatrix parse_mass_matrix(const std::string& name);      //!< analytic, sampled
FitSolver parse_fit_solver(const std::string& name);        //!< auto, cholmod
const char* fit_method_name(FitMethod m);
const char* regularizer_name(Regularizer r);
const char* mass_matrix_name(MassMatrix m);
const char* fit_solver_name(FitSolver s);

struct FitOptions {
  FitMethod method = FitMethod::LeastSquares;
  Regularizer regularizer = Regularizer::Edge;
  double alpha = 0.1;  //!< weight of the regulariser; 0 is the plain least-squares optimum
  MassMatrix mass = MassMatrix::Analytic;
  //! Analytic mass: estimate b as A·prior + Monte Carlo of ∫h_i (f − g_prior), so that b's
  //! sampling error scales with f − g_prior instead of f (off: the paper's plain estimate).
  bool control_variate = true;
  FitSolver solver = FitSolver::Auto;
  double cg_tolerance = 1e-10;  //!< relative residual of the Jacobi-scaled system, per column
  int cg_max_iterations = 100;  //!< beyond this (or when CG predicts it), CHOLMOD takes over
  int threads = 0;     //!< for the iterative solve; 0: every core (the result does not depend on it)
};

struct FitStats {
  size_t unknowns = 0;             //!< render vertices
  size_t unsupported = 0;          //!< vertices no sampled face touches: they keep the prior
  size_t system_nonzeros = 0;      //!< of A + αR (both triangles)
  size_t factor_nonzeros = 0;      //!< of the Cholesky factor L (0 when CG solved it)
  std::string solver;              //!< "cg" or "cholmod": what produced the values
  int cg_iterations = 0;           //!< of the slowest column, also when CG gave up
  double solve_memory_mib = 0;     //!< system plus factor (or CG's vectors) plus right-hand sides, as stored
  double stabilizer = 0;           //!< λ of the pull towards the prior that was needed (0: none)
  double seconds_assemble = 0, seconds_factor = 0, seconds_solve = 0;
  std::string warning;             //!< non-empty when the fallback was used
};

//! A: ∫ h_i h_j over faces with samples (analytic: area/6 on the diagonal, area/12 off it;
//! sampled: Σ_j w_j h_i(p_j) h_k(p_j), what the samples alone can see). #V by #V.
SparseMatrixd mass_matrix(const Mesh& mesh, const SurfaceSamples& samples, MassMatrix kind);

//! R_grad = Σ_t a_t² G_tᵀ G_t, G_t the 3×#V gradient of the hat functions on face t: the
//! area-scaled gradient energy of equation (12). Annihilates constants.
SparseMatrixd gradient_regularizer(const Mesh& mesh);

//! R_edge = Σ over interior non-crease edges (a_t + a_u)(F_t − F_u)ᵀ(F_t − F_u), F = √a·G:
//! penalises jumps of the gradient across an edge shared (with the same render vertices) by
//! exactly two faces. Annihilates every linear function on a flat mesh.
//! \param interior_edges if given, receives the number of edges that contributed
SparseMatrixd edge_regularizer(const Mesh& mesh, size_t* interior_edges = nullptr);

//! The signal at the samples reduced face by face: all the fit needs of it, 3/(samples per face)
//! of its size. Row 3f + c is Σ w_k h_c(p_k) f(p_k) over face f's samples k.
struct FaceMoments {
  RowMatrixXd rows;  //!< 3#F by K
};

//! The three moment rows of samples first .. last-1, all on one face, from their values (one
//! row of K per sample, row-major) into out (3 rows of K, row-major, overwritten). A face's
//! moments are the sum over any partition of its samples.
void sample_moments(const SurfaceSamples& samples, size_t first, size_t last, const double* values, Eigen::Index K,
                    double* out);

//! Every face's moments from stored sample values.
//! \param values #S by K, the signal at the samples
FaceMoments face_moments(const Mesh& mesh, const SurfaceSamples& samples, const RowMatrixXd& values);

//! b = ∫ h_i f by Monte Carlo over the samples: #V by K.
//! \param values #S by K, the signal at the samples
RowMatrixXd fit_right_hand_side(const Mesh& mesh, const SurfaceSamples& samples, const RowMatrixXd& values);

//! The regularised least-squares system (A + αR) x = b over the vertices the samples support,
//! Jacobi-scaled: M = S(A + αR)S and y = S⁻¹x, S = diag(A + αR)^(-1/2). Vertices that no sampled
//! face touches are fixed at the prior, their columns moved to the right-hand side.
struct FitSystem {
  RowSparseMatrixd matrix;         //!< n by n, M, both triangles
  RowMatrixXd rhs;                 //!< n by K, S·b
  Eigen::VectorXd scale;           //!< n: the diagonal of S
  Eigen::VectorXd lumped;          //!< n: the lumped mass ∫h_i of each unknown (the stabiliser's weight)
  std::vector<Eigen::Index> slot;  //!< #V: a vertex's unknown, or -1 when it is fixed at the prior
};

//! Assembles the system of FitMethod::LeastSquares (the other methods need none).
//! \param prior #V by K: the point-sampled values; with the control variate, b is estimated around them
//! \throw InputError for bad shapes, non-finite values or α
FitSystem assemble_fit_system(const Mesh& mesh, const SurfaceSamples& samples, const FaceMoments& moments,
                              const RowMatrixXd& prior, const FitOptions& options, FitStats* stats = nullptr);

//! Solves a FitSystem for all K right-hand sides at once. With the analytic mass matrix and
//! FitSolver::Auto: block conjugate gradients started at the prior (the scaled system is well
//! conditioned on any mesh). Otherwise, or when CG stalls: one CHOLMOD supernodal Cholesky
//! factorisation, kept for every later solve. A singular system (α = 0 with a mass matrix that
//! cannot see a vertex) is stabilised by a pull towards the prior, λ·D(x − prior), with the
//! smallest λ that factorises; FitStats says so. Keeps a reference to `system`.
class FitSystemSolver {
 public:
  FitSystemSolver(const FitSystem& system, const FitOptions& options);
  ~FitSystemSolver();
  FitSystemSolver(const FitSystemSolver&) = delete;
  FitSystemSolver& operator=(const FitSystemSolver&) = delete;
  //! x, #V by K (all finite): the solution, with fixed vertices at `prior`. `stats` gains the
  //! solve's figures (its other fields are kept).
  //! \throw SolverError if no stabilised system factorises
  RowMatrixXd solve(const RowMatrixXd& prior, FitStats* stats = nullptr);

 private:
  class Cholesky;
  void factorize(FitStats& stats);
  const FitSystem& system_;
  FitOptions options_;
  std::unique_ptr<Cholesky> cholesky_;
  double stabilizer_ = 0;
  size_t factor_entries_ = 0;
};

//! Vertex values from the signal's face moments at the samples.
//!  - Point: the prior.
//!  - Average: D⁻¹b, D the lumped mass (∫ h_i): the barycentric-weighted average of the samples.
//!  - LeastSquares: assemble_fit_system, then FitSystemSolver.
//! A vertex no sampled face touches keeps its prior value.
//! \param prior #V by K: the point-sampled values (what Point returns)
//! \return #V by K, all finite
//! \throw SolverError if no stabilised system factorises, InputError for bad shapes or α
RowMatrixXd fit_vertex_values(const Mesh& mesh, const SurfaceSamples& samples, const FaceMoments& moments,
                              const RowMatrixXd& prior, const FitOptions& options, FitStats* stats = nullptr);

//! The same from stored sample values (#S by K).
RowMatrixXd fit_vertex_values(const Mesh& mesh, const SurfaceSamples& samples, const RowMatrixXd& values,
                              const RowMatrixXd& prior, const FitOptions& options, FitStats* stats = nullptr);

}  // namespace prtsub
