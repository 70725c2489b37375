// Spectra + sparse Cholesky: the only unit that includes them.
#include "chladni/precompute/eigensolve.hpp"

#include <Spectra/SymGEigsShiftSolver.h>
#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>
#ifdef CHLADNI_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

#include <chrono>
#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"

namespace chladni::precompute {
namespace {

#ifdef CHLADNI_HAVE_CHOLMOD
using Factor = Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower>;
constexpr const char* kFactorName = "CHOLMOD supernodal LLT";
#else
using Factor = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>;
constexpr const char* kFactorName = "Eigen SimplicialLDLT";
#endif

// y = (K - sigma M)^-1 x, the operator Spectra's shift-invert mode needs.
class ShiftInvert {
 public:
  using Scalar = double;
  ShiftInvert(const SparseMatrix& K, const SparseMatrix& M) : K_(K), M_(M) {
#ifdef CHLADNI_HAVE_CHOLMOD
    factor_.cholmod().print = 0;  // failures are reported through our exceptions
#endif
  }
  Eigen::Index rows() const {
    return K_.rows();
  }
  Eigen::Index cols() const {
    return K_.cols();
  }
  void set_shift(double sigma) {
    if (sigma == sigma_ && factored_) return;
    const SparseMatrix A = K_ - sigma * M_;
    factor_.compute(A);
    if (factor_.info() != Eigen::Success)
      throw InputError("the sparse factorization of K - sigma M (" + std::to_string(K_.rows()) +
                       " DOFs, " + std::to_string(K_.nonZeros()) +
                       " entries) failed: the problem is too large for the factorization or the "
                       "stiffness is not positive semi-definite; lower --max-freq or raise "
                       "--max-tet-volume");
    sigma_ = sigma, factored_ = true;
  }
  void perform_op(const double* x, double* y) const {
    Eigen::Map<const Eigen::VectorXd> xv(x, K_.rows());
    Eigen::Map<Eigen::VectorXd> yv(y, K_.rows());
    yv = factor_.solve(xv);
  }

 private:
  const SparseMatrix& K_;
  const SparseMatrix& M_;
  Factor factor_;
  double sigma_ = 0;
  bool factored_ = false;
};

// y = M x with the full symmetric storage (faster than a self-adjoint view).
class MassProduct {
 public:
  using Scalar = double;
  explicit MassProduct(const SparseMatrix& M) : M_(M) {}
  Eigen::Index rows() const { return M_.rows(); }
  Eigen::Index cols() const { return M_.cols(); }
  void perform_op(const double* x, double* y) const {
    Eigen::Map<const Eigen::VectorXd> xv(x, M_.rows());
    Eigen::Map<Eigen::VectorXd> yv(y, M_.rows());
    yv.noalias() = M_ * xv;
  }

 private:
  const SparseMatrix& M_;
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::string factorization_name() {
  return kFactorName;
}

EigenResult solve_modes(const SparseMatrix& K, const SparseMatrix& M, const Eigen::MatrixXd& rigid,
                        const EigenOptions& o,
                        const std::function<void(const std::string&)>& status) {
  const Eigen::Index n = K.rows();
  if (n != M.rows() || rigid.rows() != n || rigid.cols() != 6)
    throw InternalError("solve_modes: K, M and the rigid modes differ in size");
  if (!(o.max_frequency > 0) || !(o.shift_hz > 0))
    throw InputError("max frequency and shift must be > 0");
  const double two_pi = 2 * std::numbers::pi;
  double sigma = -std::pow(two_pi * o.shift_hz, 2);
  const double lambda_max = std::pow(two_pi * o.max_frequency, 2);

  EigenResult r;
  r.factorization = kFactorName;
  auto t0 = std::chrono::steady_clock::now();
  ShiftInvert op(K, M);
  // Round-off on a badly shaped mesh can make K - sigma M indefinite along the rigid motions
  // when |sigma| is tiny next to K's scale: move the shift further down and retry.
  for (int attempt = 0;; ++attempt) {
    try {
      op.set_shift(sigma);
      break;
    } catch (const InputError&) {
      if (attempt == 4) throw;
      sigma *= 100;
      if (status) status("factorization failed; retrying with shift " + std::to_string(sigma));
    }
  }
  r.shift = sigma;
  r.factor_seconds = seconds_since(t0);
  MassProduct Bop(M);

  // M-orthonormal basis of the rigid motions: Q = R L^-T with L L^T = R^T M R.
  const Eigen::MatrixXd MR = M * rigid;
  const Eigen::MatrixXd G = rigid.transpose() * MR;
  const Eigen::LLT<Eigen::MatrixXd> llt(G);
  if (llt.info() != Eigen::Success) throw InternalError("rigid-body motions are degenerate");
  const Eigen::MatrixXd MQ = llt.matrixL().solve(MR.transpose()).transpose();  // M Q

  const Eigen::Index max_nev = std::min<Eigen::Index>(n - 2, Eigen::Index(o.mode_cap) + 6);
  Eigen::Index nev = o.modes > 0 ? Eigen::Index(o.modes) + 6 : std::min<Eigen::Index>(46, max_nev);
  if (o.modes > 0 && nev > max_nev)
    throw InputError("asked for " + std::to_string(o.modes) + " modes but the mesh has only " +
                     std::to_string(n) + " degrees of freedom (or the cap " +
                     std::to_string(o.mode_cap) + " is lower)");
  t0 = std::chrono::steady_clock::now();
  Eigen::VectorXd evals;
  Eigen::MatrixXd evecs;
  for (;;) {
    const Eigen::Index ncv =
        std::min<Eigen::Index>(n, std::max<Eigen::Index>(2 * nev + 1, nev + 20));
    if (status)
      status("Lanczos for " + std::to_string(nev) + " modes (" + std::to_string(ncv) + " vectors)");
    Spectra::SymGEigsShiftSolver<ShiftInvert, MassProduct, Spectra::GEigsMode::ShiftInvert> eigs(
        op, Bop, nev, ncv, sigma);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestMagn, 1000, o.tolerance,
                 Spectra::SortRule::SmallestAlge);
    ++r.solves;
    r.operations += eigs.num_operations();
    if (eigs.info() != Spectra::CompInfo::Successful)
      throw InternalError("the eigen-solver did not converge for " + std::to_string(nev) +
                          " modes");
    evals = eigs.eigenvalues();
    evecs = eigs.eigenvectors();
    if (o.modes > 0 || evals(evals.size() - 1) >= lambda_max) break;
    if (nev >= max_nev) {
      r.capped = true;
      break;
    }
    // Weyl: a solid's mode count grows like f^3 (a plate's like f^2); aim a little past the band.
    const double f_top = std::sqrt(std::max(evals(evals.size() - 1), 1.0)) / two_pi;
    const double grow = std::pow(o.max_frequency / f_top, 2.0) * 1.2;
    nev = std::min<Eigen::Index>(max_nev,
                                 std::max<Eigen::Index>(2 * nev, Eigen::Index(nev * grow) + 10));
  }
  r.lanczos_seconds = seconds_since(t0);

  // Classify rigid modes by their M-weighted overlap with the rigid motions.
  std::vector<Eigen::Index> elastic;
  for (Eigen::Index j = 0; j < evals.size(); ++j) {
    Eigen::VectorXd v = evecs.col(j);
    const double mnorm = std::sqrt(v.dot(M * v));
    v /= mnorm;
    evecs.col(j) = v;
    const double overlap = (MQ.transpose() * v).norm();
    if (overlap > 0.5) {
      ++r.rigid_removed;
      r.rigid_lambda.push_back(evals(j));
    } else {
      elastic.push_back(j);
    }
  }
  if (r.rigid_removed != 6) {
    std::string hz;
    for (double l : r.rigid_lambda)
      hz += " " + std::to_string(std::sqrt(std::abs(l)) / two_pi).substr(0, 8);
    throw InputError("found " + std::to_string(r.rigid_removed) +
                     " modes that move the body almost rigidly instead of 6 (at" + hz +
                     " Hz): the solid is not one well-connected piece (parts joined only at an "
                     "edge or a vertex, or slivers from a poor surface)");
  }
  for (Eigen::Index j : elastic) {
    if (o.modes == 0 && evals(j) > lambda_max) break;
    if (o.modes > 0 && r.lambda.size() == o.modes) break;
    r.lambda.push_back(evals(j));
  }
  r.vectors.resize(n, Eigen::Index(r.lambda.size()));
  for (std::size_t i = 0; i < r.lambda.size(); ++i) {
    r.vectors.col(Eigen::Index(i)) = evecs.col(elastic[i]);
    const Eigen::VectorXd Kv = K * r.vectors.col(Eigen::Index(i));
    const Eigen::VectorXd res = Kv - r.lambda[i] * (M * r.vectors.col(Eigen::Index(i)));
    r.residual.push_back(res.norm() / Kv.norm());
  }
  return r;
}

}  // namespace chladni::precompute
