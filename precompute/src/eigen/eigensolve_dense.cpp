#include "eigensolve_dense.hpp"

#include <Eigen/Eigenvalues>

#include "chladni/core/error.hpp"

namespace chladni::precompute {

void dense_modes(const SparseMatrix& K, const SparseMatrix& M, Eigen::VectorXd& lambda,
                 Eigen::MatrixXd& vectors) {
  const Eigen::MatrixXd Kd(K), Md(M);
  // Cholesky of M, then the symmetric standard problem (LAPACK-style, Eigen's own).
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(
      Kd.selfadjointView<Eigen::Lower>(), Md.selfadjointView<Eigen::Lower>());
  if (es.info() != Eigen::Success)
    throw InputError("the mass matrix is not positive definite (degenerate elements?)");
  lambda = es.eigenvalues();
  vectors = es.eigenvectors();
}

}  // namespace chladni::precompute
