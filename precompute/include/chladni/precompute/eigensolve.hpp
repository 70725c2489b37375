#pragma once
// The generalized symmetric eigenproblem K v = lambda M v by shift-invert Lanczos (Spectra) over a
// sparse Cholesky factorization of K - sigma M (CHOLMOD when built with it, else Eigen's
// SimplicialLDLT). Only eigensolve.cpp includes Spectra and CHOLMOD.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "chladni/precompute/fem.hpp"
#include "chladni/precompute/memory_budget.hpp"

namespace chladni::precompute {

struct EigenOptions {
  /// First N elastic modes in [min_frequency, max_frequency], with those below min_frequency
  /// before them, none above max_frequency (block Lanczos; the other methods may return some
  /// above it); 0: all below max_frequency.
  std::size_t modes = 0;
  double max_frequency = 20000;  ///< Hz, undamped: the top of the band
  /// Hz, undamped: modes below it (which precompute drops) do not count toward `modes`, so a
  /// large object asked for N modes gets N it can hear.
  double min_frequency = 0;
  std::size_t mode_cap = 2000;  ///< most elastic modes ever computed
  /// With modes == 0: about how many modes lie below max_frequency (Weyl's law; 0: unknown).
  /// The memory check then counts a Lanczos basis that can hold them.
  std::size_t expected_modes = 0;
  double shift_hz = 20;     ///< sigma = -(2 pi shift_hz)^2: below zero, so K - sigma M is SPD
  double tolerance = 1e-8;  ///< relative Ritz residual at convergence
  /// BlockLanczos (default): our block Lanczos on the same operator, blocks of `block` vectors.
  /// Spectra: Spectra's SymEigsSolver (single-vector implicitly restarted Lanczos).
  enum class Method { BlockLanczos, Spectra };
  Method method = Method::BlockLanczos;
  Eigen::Index block = 8;
  /// Bytes the eigen-solve may take at its peak (the factor, with K and M and either the copies
  /// the factorization makes or the Lanczos basis and the modes); 0: no limit. The symbolic
  /// analysis says what the factor needs before any of it is allocated; above the budget, or
  /// when the basis the budget leaves fills before the modes converge, solve_modes refuses
  /// (BudgetError) with the numbers.
  double max_memory = 0;
  /// A fill-reducing ordering of the mesh's nodes (check_memory_for_mesh's), reused by the
  /// factorization so the graph is ordered once; empty: the factorization finds one.
  std::vector<std::int64_t> node_ordering;
};

struct EigenResult {
  std::vector<double> lambda;    ///< omega^2 of the elastic modes, ascending
  Eigen::MatrixXd vectors;       ///< M-normalized, one column per elastic mode
  std::vector<double> residual;  ///< ||K v - lambda M v|| / ||K v||
  std::size_t rigid_removed = 0;
  std::vector<double> rigid_lambda;  ///< eigenvalues of the removed rigid modes
  std::size_t solves = 0;            ///< Lanczos runs (more than one when the band grew)
  std::size_t operations = 0;        ///< triangular solves
  bool capped = false;               ///< mode_cap stopped the search below max_frequency
  std::string factorization;         ///< "CHOLMOD supernodal LLT" or "Eigen SimplicialLDLT"
  double shift = 0;                  ///< sigma used (rad^2/s^2)
  double factor_seconds = 0, lanczos_seconds = 0;
  /// From the symbolic analysis (0 where the factorization cannot say in advance).
  double factor_entries = 0, factor_bytes = 0, factor_flops = 0;
  /// The numeric factorization's time predicted from its flops and the BLAS's measured dense
  /// rate (rough: within about a factor of two; factor_seconds also holds the analysis).
  double factor_seconds_estimate = 0;
  double matrix_bytes = 0;   ///< K, M and the copies the factorization makes
  double basis_bytes = 0;    ///< the Lanczos basis' share of memory
  double solve_seconds = 0;  ///< part of lanczos_seconds spent in the triangular solves
};

/// `rigid` holds the six rigid-body motions (rigid_body_modes): computed modes whose M-weighted
/// projection onto them exceeds 1/2 are rigid; exactly six must be found, and none may be kept.
EigenResult solve_modes(const SparseMatrix& K, const SparseMatrix& M, const Eigen::MatrixXd& rigid,
                        const EigenOptions& options,
                        const std::function<void(const std::string&)>& status = {});

/// Before assembly: the memory solve_modes will need for `mesh`'s K and M (CHOLMOD's analysis
/// of the node graph, scaled to three DOFs per node), in bytes. Throws BudgetError with the
/// numbers when it exceeds options.max_memory; 0 without a budget or without CHOLMOD. The
/// ordering the analysis found goes to `node_ordering`, for EigenOptions::node_ordering.
double check_memory_for_mesh(const FemMesh& mesh, const EigenOptions& options,
                             std::vector<std::int64_t>* node_ordering = nullptr);
/// Before meshing: a lower bound on the memory solve_modes will need for a mesh of at least
/// `tetrahedra` elements of the same solid, extrapolated from two coarser meshes of it (`coarse`
/// smaller than `sample`). Throws BudgetError ("at least ...") when even that exceeds
/// options.max_memory, so an asset far over the budget is refused in seconds instead of after
/// meshing; 0 when it cannot say.
double check_memory_extrapolated(const FemMesh& coarse, const FemMesh& sample, double tetrahedra,
                                 const EigenOptions& options);
/// Before meshing `surface` (enclosing `solid` m^3) under `max_volume` with `tet`'s quality:
/// check_memory_extrapolated on coarser meshes of it (seconds), so an asset far over the
/// budget is refused before minutes of meshing. The lower bound in bytes; 0 where the mesh is
/// close to the coarsest one (quick to make), without a budget, or when it cannot say.
double check_memory_for_surface(const SurfaceMesh& surface, double solid, double max_volume,
                                int order, const TetOptions& tet, const EigenOptions& options);
/// Which factorization solve_modes uses in this build.
std::string factorization_name();

}  // namespace chladni::precompute
