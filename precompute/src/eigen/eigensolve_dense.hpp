#pragma once
// Every eigenpair of a small generalized problem, densely: for tiny solids and coarse meshes,
// where Lanczos would need more vectors than the problem has.
#include <Eigen/Dense>

#include "chladni/precompute/fem.hpp"

namespace chladni::precompute {

/// Problems up to this many degrees of freedom are solved densely (about 0.1 s at the limit).
inline constexpr Eigen::Index kDenseDofs = 600;

/// All eigenpairs of K v = lambda M v (M symmetric positive definite), lambda ascending, v
/// M-normalized.
void dense_modes(const SparseMatrix& K, const SparseMatrix& M, Eigen::VectorXd& lambda,
                 Eigen::MatrixXd& vectors);

}  // namespace chladni::precompute
