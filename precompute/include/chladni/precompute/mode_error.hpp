#pragma once
// A-posteriori error of each mode's frequency from one solve. The strain recovered from the
// element strains by superconvergent patch recovery (Zienkiewicz & Zhu 1992) stands in for the
// exact one. For a conforming discretization with a consistent mass,
//   lambda_h - lambda = ||u - u_h||_a^2 - lambda ||u - u_h||_M^2   (Babuska & Osborn 1991),
// whose first term dominates, so (f_h - f) / f ~ eta^2 / (2 lambda_h) with
//   eta^2 = sum over elements of the integral of (eps* - eps_h) : C : (eps* - eps_h).
// The element terms also say where the mesh is too coarse for a mode (thin walls, torsion).
#include <Eigen/Core>
#include <vector>

#include "chladni/core/material.hpp"
#include "chladni/precompute/fem.hpp"

namespace chladni::precompute {

struct ModeErrors {
  /// Per mode: estimated (f_h - f) / f (measured against finer solves: 0.7 to 1.3 times the
  /// actual error on the bundled bar, docs/validation.md). Blind to what a mesh of one layer
  /// cannot carry (a square bar's twist); solve_to_tolerance confirms such meshes.
  std::vector<double> relative;
  /// Per element: its largest share of any mode's relative estimate (sum over elements of one
  /// mode's shares is that mode's `relative`).
  std::vector<double> element;
};

/// `shapes` must be `mesh`'s M-normalized eigenvectors, one column per mode, with `omega2` their
/// eigenvalues (solve_modes' EigenResult::vectors and ::lambda). threads: 0 = all.
ModeErrors estimate_mode_errors(const FemMesh& mesh, const Material& material,
                                const std::vector<double>& omega2, const Eigen::MatrixXd& shapes,
                                int threads = 0);

}  // namespace chladni::precompute
