#pragma once
// The shift-invert operator of the eigen-solve over a sparse Cholesky factor (CHOLMOD when built
// with it, else Eigen's SimplicialLDLT). Included by eigensolve.cpp and eigen_memory.cpp.
#include <Eigen/SparseCholesky>
#include <chrono>
#include <string>
#include <type_traits>

#include "chladni/core/error.hpp"
#include "chladni/precompute/fem.hpp"
#include "cholmod_factor.hpp"  // FactorEstimate in every build; CholmodFactor with CHOLMOD
#include "symmetric_product.hpp"

namespace chladni::precompute {

// K - sigma M = P^T L L^T P (sigma < 0, so the matrix is SPD). Lanczos then runs on the standard
// symmetric operator C = L^-1 P M P^T L^-T, whose eigenpairs are 1 / (lambda - sigma) and
// y = L^T P v: the same spectrum as shift-invert, but with Euclidean inner products, so no
// mass-matrix product per inner product and per reorthogonalization pass (which dominated the
// generalized mode of Spectra).
#ifdef CHLADNI_HAVE_CHOLMOD
constexpr const char* kFactorName = "CHOLMOD supernodal LLT";

// CHOLMOD's supernodal LLT with every call checked (cholmod_factor.cpp).
class Factor {
 public:
  FactorEstimate analyze(const SparseMatrix& A, int block,
                         const std::vector<std::int64_t>* block_order) {
    return chol_.analyze(A, block, block_order);
  }
  std::vector<std::int64_t> ordering() const { return chol_.ordering(); }
  // A + beta B, B's pattern within A's
  bool factor(const SparseMatrix& A, double beta, const SparseMatrix& B) {
    return chol_.factorize(A, beta, &B);
  }
  // x <- P^T L^-T x  and  x <- L^-1 P x
  template <class Dense>
  void upper_solve(Dense& x) {
    chol_.upper_solve(x.data(), long(x.rows()), long(x.cols()));
  }
  template <class Dense>
  void lower_solve(Dense& x) {
    chol_.lower_solve(x.data(), long(x.rows()), long(x.cols()));
  }

 private:
  CholmodFactor chol_;
};
#else
constexpr const char* kFactorName = "Eigen SimplicialLDLT";

// P A P^T = L D L^T; the split factor is L D^1/2.
class Factor {
 public:
  // unknown before factorizing
  FactorEstimate analyze(const SparseMatrix&, int, const std::vector<std::int64_t>*) { return {}; }
  std::vector<std::int64_t> ordering() const { return {}; }
  bool factor(const SparseMatrix& A, double beta, const SparseMatrix& B) {
    ldlt_.compute(SparseMatrix(A + beta * B));
    if (ldlt_.info() != Eigen::Success || (ldlt_.vectorD().array() <= 0).any()) return false;
    sqrt_d_ = ldlt_.vectorD().array().sqrt();
    return true;
  }
  template <class Dense>
  void upper_solve(Dense& x) {
    x = sqrt_d_.cwiseInverse().asDiagonal() * x;
    ldlt_.matrixU().solveInPlace(x);
    x = ldlt_.permutationPinv() * x;
  }
  template <class Dense>
  void lower_solve(Dense& x) {
    x = ldlt_.permutationP() * x;
    ldlt_.matrixL().solveInPlace(x);
    x = sqrt_d_.cwiseInverse().asDiagonal() * x;
  }

 private:
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower> ldlt_;
  Eigen::VectorXd sqrt_d_;
};
#endif

class SplitShiftInvert {
 public:
  using Scalar = double;
  SplitShiftInvert(const SparseMatrix& K, const SparseMatrix& M) : K_(K), M_(M), w_(K.rows()) {}
  Eigen::Index rows() const { return K_.rows(); }
  Eigen::Index cols() const { return K_.cols(); }
  // The pattern of K - sigma M is K's (assemble() gives M the same one; the factorization checks
  // that M's lies within it) for every sigma: analyzed once, ordered by nodes (three interleaved
  // displacements each, as assemble() numbers them), in `nodes`' order where it holds one.
  FactorEstimate analyze(const std::vector<std::int64_t>& nodes) {
    return factor_.analyze(K_, 3, &nodes);
  }
  void factor(double sigma) {
    if (!factor_.factor(K_, -sigma, M_))
      throw InputError("the sparse factorization of K - sigma M (" + std::to_string(K_.rows()) +
                       " DOFs, " + std::to_string(K_.nonZeros()) +
                       " entries) failed: the problem is too large for the factorization or the "
                       "stiffness is not positive semi-definite; lower --max-freq or raise "
                       "--max-tet-volume");
  }
  // y = C x, for Spectra.
  void perform_op(const double* x, double* y) const {
    w_ = Eigen::Map<const Eigen::VectorXd>(x, rows());
    apply(w_);
    Eigen::Map<Eigen::VectorXd>(y, rows()) = w_;
  }
  // W = C V for a block of vectors: the factor and M are read once for all columns.
  void apply_block(const Eigen::MatrixXd& V, Eigen::MatrixXd& W) const {
    W = V;
    apply(W);
  }
  // Each column y <- P^T L^-T y, a vector of the original problem.
  void to_modes(Eigen::MatrixXd& Y) { factor_.upper_solve(Y); }
  mutable double solve_seconds = 0;

 private:
  // X <- C X = L^-1 P M P^T L^-T X
  template <class Dense>
  void apply(Dense& X) const {
    const auto t0 = std::chrono::steady_clock::now();
    factor_.upper_solve(X);
    if constexpr (std::is_same_v<Dense, Eigen::MatrixXd>) {
      symmetric_product(M_, X, mx_);
      factor_.lower_solve(mx_);
      X.swap(mx_);
    } else {
      Dense MX = M_ * X;
      factor_.lower_solve(MX);
      X = std::move(MX);
    }
    solve_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  const SparseMatrix& K_;
  const SparseMatrix& M_;
  mutable Factor factor_;  // CHOLMOD's workspace changes during solves
  mutable Eigen::VectorXd w_;
  mutable Eigen::MatrixXd mx_;  // M X for a block, kept between applications
};

}  // namespace chladni::precompute
