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
//! Auto: chosen per system before any iteration (FitSystemSolver). Cg: conjugate gradients with
//! the unit diagonal's scaling; Multigrid: with a smoothed-aggregation multigrid cycle as the
//! preconditioner; both fall back to CHOLMOD if they stall, and need the analytic mass matrix
//! (CHOLMOD for the sampled one). Cholmod: always CHOLMOD's Cholesky factorisation.
enum class FitSolver { Auto, Cg, Multigrid, Cholmod };
//! What the fit may not do that the point samples never do: go negative.
//!  - Off: nothing.
//!  - Constant: each vertex's DC coefficient is at least 0, so no constant light (of any colour
//!    or strength) gives negative radiance anywhere, interpolated or not.
//!  - Directions: also pull each vertex towards its prior until its transfer function is at least
//!    min(0, the prior's minimum) at 128 directions, so that narrow lights (a sun) do not either.
enum class NonNegative { Off, Constant, Directions };

FitMethod parse_fit_method(const std::string& name);        //!< point, average, lsq
Regularizer parse_regularizer(const std::string& name);     //!< edge, gradient
MassMatrix parse_mass_matrix(const std::string& name);      //!< analytic, sampled
FitSolver parse_fit_solver(const std::string& name);        //!< auto, cg, multigrid, cholmod
const char* fit_method_name(FitMethod m);
const char* regularizer_name(Regularizer r);
const char* mass_matrix_name(MassMatrix m);
const char* fit_solver_name(FitSolver s);
const char* non_negative_name(NonNegative n);

class Multigrid;
class StiffBlock;

struct FitOptions {
  FitMethod method = FitMethod::LeastSquares;
  Regularizer regularizer = Regularizer::Edge;
  //! weight of the regulariser; 0 is the plain least-squares optimum. The paper recommends 0.1
  //! for its estimator; weighed by noise, 0.04 measured best over the shared scenes (BENCHMARKS.md)
  double alpha = 0.04;
  MassMatrix mass = MassMatrix::Analytic;
  //! Analytic mass: estimate b as A·prior + Monte Carlo of ∫h_i (f − g_prior), so that b's
  //! sampling error scales with f − g_prior instead of f (off: the paper's plain estimate).
  bool control_variate = true;
  FitSolver solver = FitSolver::Auto;
  //! CG's relative residual per column (of the Jacobi-scaled system). 1e-6 moves no stored value
  //! by more than 1.4e-4 of the largest from the exact solve (armadillo; eval's error the same to
  //! four digits: bench/fit_tolerance.sh), in about 60% of the iterations 1e-10 takes.
  double cg_tolerance = 1e-6;
  int cg_max_iterations = 100;  //!< beyond this (or when CG predicts it), CHOLMOD takes over
  //! A row is stiff when the mass holds under this share of its (scaled) diagonal; CG solves the
  //! stiff rows' block directly in each iteration. 0: none (Jacobi alone). Measured with
  //! bench/stiff_block.sh (BENCHMARKS.md "Stiff rows solved directly").
  double stiff_mass = 0.2;
  int threads = 0;     //!< for the iterative solve; 0: every core (the result does not depend on it)
  //! Keep of each vertex's correction (fit − prior) the share its noise allows: where the
  //! correction is mostly the samples' noise, the point sample stays; where it is systematic
  //! (a shadow inside a face), the fit does. Needs the moments' and the prior's variances.
  bool weigh_by_noise = true;
  NonNegative non_negative = NonNegative::Constant;
  //! LeastSquares on shadowed SH transfer of this order (values of channels × order² columns;
  //! 0: any other signal). t_u(n)'s curvature in the normal, as far as each point is open, is then
  //! known: the prior is corrected by its exact projection, P(w·t_u) − w·t_u(n_i) with w the
  //! vertex's open share (unshadowed_projection), before the fit runs around it (docs/fit.md).
  int unshadowed_order = 0;
};

struct FitStats {
  size_t unknowns = 0;             //!< render vertices
  size_t unsupported = 0;          //!< vertices no sampled face touches: they keep the prior
  size_t system_nonzeros = 0;      //!< of A + αR (both triangles)
  size_t factor_nonzeros = 0;      //!< of the Cholesky factor L (0 when CG solved it)
  //! share of the unknowns whose diagonal is over 80% regulariser (stiff rows): CG solves their
  //! block directly in each iteration (its preconditioner), unless that block's factor is dear
  double stiff_share = 0;
  size_t stiff_rows = 0;                //!< rows in CG's directly solved block (0: Jacobi alone)
  size_t stiff_factor_entries = 0;      //!< that block's Cholesky factor
  //! the whole system's symbolic analysis, when it ran (the stiff block was too dear): CHOLMOD
  //! instead of CG where this count is small
  size_t predicted_factor_entries = 0;
  std::string solver;              //!< "cg", "cg-multigrid" or "cholmod": what produced the values
  int multigrid_levels = 0;        //!< of the multigrid preconditioner (0: none)
  double multigrid_operator_complexity = 0;  //!< its non-zeros over all levels / the system's
  int cg_iterations = 0;           //!< of the slowest column, also when CG gave up
  double solve_memory_mib = 0;     //!< system plus factor (or CG's vectors) plus right-hand sides, as stored
  double stabilizer = 0;           //!< λ of the pull towards the prior that was needed (0: none)
  double seconds_assemble = 0, seconds_factor = 0, seconds_solve = 0;
  //! Parts of seconds_assemble (the system's): the sums over faces (right-hand sides and masses),
  //! the regulariser's edge blocks (with the unknowns' numbering), the matrix's rows
  double seconds_assemble_sums = 0, seconds_assemble_edges = 0, seconds_assemble_rows = 0;
  //! weigh_by_noise: the mean share of the fit's correction kept (1: the fit, 0: the prior)
  double kept_correction = 1;
  size_t limited_vertices = 0;     //!< non_negative: vertices whose values it changed
  //! unshadowed_order: the exact projection's CG passes and seconds (0 when it did not run)
  int unshadowed_iterations = 0;
  double seconds_unshadowed = 0;
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
  //! 3#F, or empty when unknown: the estimated variance of row 3f + c (summed over its K values)
  std::vector<double> variance;
};

//! The three moment rows of samples first .. last-1, all on one face, from their values (one
//! row of K per sample, row-major) into out (3 rows of K, row-major, overwritten). A face's
//! moments are the sum over any partition of its samples.
void sample_moments(const SurfaceSamples& samples, size_t first, size_t last, const double* values, Eigen::Index K,
                    double* out);

//! The moments of two sample sets as those of their union (merge_surface_samples(a, b)): face by
//! face the count-weighted mean of the two estimates, and its variance.
//! \throw InputError for shapes that do not match
FaceMoments merge_face_moments(const SurfaceSamples& a, const FaceMoments& ma, const SurfaceSamples& b, const FaceMoments& mb);

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
  //! n by 3 with FitSolver::Multigrid (else empty): each unknown's position, relative to the
  //! mesh's centre in units of its size; the multigrid's near-null vectors are built from them
  Eigen::MatrixX3d points;
  std::vector<Eigen::Index> slot;  //!< #V: a vertex's unknown, or -1 when it is fixed at the prior
};

//! Assembles the system of FitMethod::LeastSquares (the other methods need none).
//! \param prior #V by K: the point-sampled values; with the control variate, b is estimated around them
//! \throw InputError for bad shapes, non-finite values or α
FitSystem assemble_fit_system(const Mesh& mesh, const SurfaceSamples& samples, const FaceMoments& moments,
                              const RowMatrixXd& prior, const FitOptions& options, FitStats* stats = nullptr);

//! Solves a FitSystem for all K right-hand sides at once. With the analytic mass matrix and
//! FitSolver::Auto or Cg: block conjugate gradients started at the prior (the scaled mass is well
//! conditioned on any mesh), preconditioned by a direct solve of the stiff rows' block where the
//! regulariser makes some rows stiff (FitStats::stiff_rows; StiffBlock). Only if that block's
//! factor would be dear does Auto let CHOLMOD's symbolic analysis of the whole system choose
//! between it and Jacobi CG; chosen before any iteration. With the sampled mass, FitSolver::Cholmod,
//! or if CG stalls after all: one CHOLMOD supernodal Cholesky factorisation, kept for every later
//! solve. FitSolver::Multigrid preconditions CG by a multigrid cycle instead (built once, kept). A singular system (α = 0 with a mass matrix that
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
  void analyze(FitStats& stats);
  void factorize(FitStats& stats);
  std::unique_ptr<Multigrid> multigrid_;  // FitSolver::Multigrid's hierarchy, built at the first solve
  std::unique_ptr<StiffBlock> stiff_;     // CG's preconditioner, built at the first solve
  bool stiff_tried_ = false;
  const FitSystem& system_;
  FitOptions options_;
  std::unique_ptr<Cholesky> cholesky_;
  SparseMatrixd lower_;
  bool factored_ = false;
  double predicted_factor_entries_ = 0;
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
//! \param prior_variance #V estimated variances of the prior's rows (shadowed_transfer's), or null:
//!        without it (or without moments.variance) weigh_by_noise does nothing
RowMatrixXd fit_vertex_values(const Mesh& mesh, const SurfaceSamples& samples, const FaceMoments& moments,
                              const RowMatrixXd& prior, const FitOptions& options, FitStats* stats = nullptr,
                              const std::vector<double>* prior_variance = nullptr);

//! The prior as the least-squares path fits around it: with options.unshadowed_order, corrected by
//! the known part's exact projection, P(w·t_u) − w·t_u(n_i) (w each vertex's open share); the prior
//! itself otherwise. Several fits of one prior (other α, say) share it: fit them with
//! unshadowed_order 0. `stats` gets unshadowed_iterations and seconds_unshadowed.
//! \throw InputError when the prior is not transfer of that order (channels × order² columns)
RowMatrixXd fit_prior(const Mesh& mesh, const RowMatrixXd& prior, const FitOptions& options, FitStats* stats = nullptr);

//! The same from stored sample values (#S by K).
RowMatrixXd fit_vertex_values(const Mesh& mesh, const SurfaceSamples& samples, const RowMatrixXd& values,
                              const RowMatrixXd& prior, const FitOptions& options, FitStats* stats = nullptr);

}  // namespace prtsub
