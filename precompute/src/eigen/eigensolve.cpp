// Spectra + sparse Cholesky: the only unit that includes them.
#include "chladni/precompute/eigensolve.hpp"

#include <Spectra/SymEigsSolver.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "../huge_pages.hpp"
#include "../timing.hpp"
#include "chladni/core/error.hpp"
#include "eigen_memory.hpp"
#include "eigensolve_dense.hpp"
#include "shift_invert.hpp"

namespace chladni::precompute {
namespace {

// The BLAS's dense product rate here (flop/s, with the threads the factorization gets), from the
// best of three 512 x 512 products, measured once (about 10 ms).
double blas_rate() {
  static const double rate = [] {
    const Eigen::Index n = 512;  // this unit is built with EIGEN_USE_BLAS: the product is dgemm
    const Eigen::MatrixXd a = Eigen::MatrixXd::Constant(n, n, 1.0), b = a;
    Eigen::MatrixXd c(n, n);
    double best = 1e30;
    for (int rep = 0; rep < 3; ++rep) {
      const auto t0 = std::chrono::steady_clock::now();
      c.noalias() = a * b;
      best = std::min(best, std::max(seconds_since(t0), 1e-9));
    }
    return 2.0 * double(n * n * n) / best;
  }();
  return rate;
}

// CHOLMOD's numeric supernodal factorization runs its flops at about this share of the dense
// product's rate (measured here: 0.17 on spot.obj's 28 GFLOP, 0.2 on the bell's 213, 0.36 on the
// rotor's 3,820; small supernodes run slower), so the estimate is rough, within a factor of two.
constexpr double kSupernodalEfficiency = 0.25;

// omega^2 at the band's bottom: modes below it do not count toward the N asked for.
double band_bottom(const EigenOptions& o) {
  return std::pow(2 * std::numbers::pi * o.min_frequency, 2);
}

// Block Lanczos with full reorthogonalization on C (symmetric, eigenvalues theta > 0), for the
// largest theta: all above theta_min, at most `cap` (the first N asked for, or --mode-cap), and
// besides those each one above theta_low past the first six (a mode below the band's bottom,
// beyond the rigid motions `cap` counts), up to `cap` more: past that the body is likely in the
// wrong unit (a bar in mm read as metres has millions below 20 Hz), which precompute then says;
// about `expect` of them (0: unknown) sizes the first basis. Spectra's Lanczos is single-vector;
// applying C to blocks of vectors turns the triangular solves and the mass product, which dominate,
// from matrix-vector into matrix-matrix work (about 4x faster here).
struct BlockLanczosResult {
  Eigen::VectorXd theta;  ///< descending
  Eigen::MatrixXd Y;      ///< Ritz vectors (orthonormal)
  std::size_t applied = 0;
  Eigen::Index done = 0;  ///< converged pairs among theta
  bool converged = false;
  bool capped = false;  ///< `cap` pairs found and the band goes on
};

BlockLanczosResult block_lanczos(const SplitShiftInvert& op, double theta_min, double theta_low,
                                 Eigen::Index cap, Eigen::Index expect, double tol,
                                 Eigen::Index max_dim, Eigen::Index b,
                                 const std::function<void(const std::string&)>& status) {
  const Eigen::Index n = op.rows();
  max_dim = std::min<Eigen::Index>(max_dim, n) / b * b;
  // Room for about four vectors per pair expected from the start: growing the basis copies it.
  Eigen::MatrixXd V(
      n, std::min<Eigen::Index>(max_dim, std::max<Eigen::Index>(4 * b, 4 * expect + 2 * b)));
  advise_huge_pages(V);
  // T grows with V: max_dim is a memory bound (thousands of columns), not the usual size.
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(V.cols(), V.cols());
  std::mt19937 rng(12345);  // fixed: the same mesh gives the same modes
  std::normal_distribution<double> gauss;
  auto orthonormalize = [&](Eigen::MatrixXd& W, Eigen::Index k, Eigen::MatrixXd& R) {
    // Block classical Gram-Schmidt against V[:, 0:k], then a thin QR; columns that vanish (an
    // invariant subspace was found) are replaced by fresh random directions. The caller has
    // taken out the three-term recurrence, so what is left along the basis is round-off and one
    // pass removes it; a second runs only where a column lost more than 1/sqrt 2 of its norm
    // (the DGKS test, as in ARPACK's dsaitr). Each pass reads the whole basis twice, the cost
    // of the iteration after the solves.
    for (int pass = 0; pass < 2 && k > 0; ++pass) {
      const Eigen::RowVectorXd before = W.colwise().norm();
      W.noalias() -= V.leftCols(k) * (V.leftCols(k).transpose() * W);
      if ((W.colwise().norm().array() >= std::sqrt(0.5) * before.array()).all()) break;
    }
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(W);
    R = qr.matrixQR().topRows(W.cols()).triangularView<Eigen::Upper>();
    Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(W.rows(), W.cols());
    const double scale = std::max(R.diagonal().cwiseAbs().maxCoeff(), 1e-300);
    for (Eigen::Index c = 0; c < W.cols(); ++c) {
      if (std::abs(R(c, c)) > 1e-10 * scale) continue;
      Eigen::VectorXd x(n);
      for (Eigen::Index i = 0; i < n; ++i) x(i) = gauss(rng);
      for (int pass = 0; pass < 2; ++pass) {
        if (k > 0) x -= V.leftCols(k) * (V.leftCols(k).transpose() * x);
        x -= Q * (Q.transpose() * x);
      }
      Q.col(c) = x.normalized();
    }
    W = Q;
  };

  BlockLanczosResult out;
  Eigen::MatrixXd W(n, b), R, Bprev;
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index c = 0; c < b; ++c) W(i, c) = gauss(rng);
  orthonormalize(W, 0, R);
  V.leftCols(b) = W;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  Eigen::Index next_check = b, reported = 0;
  for (Eigen::Index k = b;; k += b) {  // V[:, 0:k] holds the basis
    const Eigen::Index j0 = k - b;
    op.apply_block(V.middleCols(j0, b), W);
    out.applied += std::size_t(b);
    const Eigen::MatrixXd A = V.middleCols(j0, b).transpose() * W;
    T.block(j0, j0, b, b) = 0.5 * (A + A.transpose());
    // The three-term recurrence: W = C V_j - V_j A_j - V_{j-1} B_{j-1}^T.
    W.noalias() -= V.middleCols(j0, b) * T.block(j0, j0, b, b);
    if (j0 >= b) W.noalias() -= V.middleCols(j0 - b, b) * T.block(j0 - b, j0, b, b);
    const bool full = k + b > max_dim;
    orthonormalize(W, k, R);
    // Ritz pairs of the current projection; residual of pair i is ||B_next S(last block, i)||,
    // with B_next from the orthonormalization above. The dense eigen-decomposition of T costs
    // O(k^3) against O(n k b) for a block's solves and reorthogonalization: done after every
    // block it dominates a band search of thousands of vectors. Done once the basis has grown
    // by a sixteenth, convergence is seen at most a sixteenth late and the decompositions add up
    // to about 6 times the last one. Also before the basis grows (its storage doubles): it may
    // already hold the modes.
    if (full || k >= next_check || k + b > V.cols()) {
      next_check = k + std::max<Eigen::Index>(b, k / 16 / b * b);
      es.compute(T.topLeftCorner(k, k));
      const Eigen::VectorXd theta = es.eigenvalues().reverse();
      const Eigen::MatrixXd S = es.eigenvectors().rowwise().reverse();
      const Eigen::VectorXd res = (R * S.bottomRows(b)).colwise().norm();
      Eigen::Index wanted = 0, done = 0, below = 0;
      while (below < k && theta(below) > theta_low) ++below;
      const Eigen::Index cap_now = cap + std::clamp<Eigen::Index>(below - 6, 0, cap);
      for (Eigen::Index i = 0; i < k; ++i) {
        if (!(theta(i) >= theta_min && i < cap_now)) break;
        ++wanted;
        done += res(i) <= tol * theta(i);
      }
      // By threshold: also require the first Ritz value below it to be converged, so that no
      // unconverged one can still rise above it (at the cap, the `cap` largest are wanted, as by
      // count); and a basis well past the wanted count, so that a multiplet wider than the block
      // has had room to appear.
      const bool bracketed =
          (wanted == cap_now || (wanted < k && res(wanted) <= tol * theta(wanted))) &&
          k >= wanted + 2 * b;
      if (status && k >= reported + 8 * b) {
        reported = k;
        status("block Lanczos: " + std::to_string(k) + " vectors, " + std::to_string(done) +
               " of " + std::to_string(wanted) + " wanted modes converged");
      }
      if ((wanted > 0 && done == wanted && bracketed) || full) {
        out.converged = done == wanted && bracketed;
        out.done = done;
        out.capped = wanted == cap_now && wanted < k && theta(wanted) >= theta_min;
        out.theta = theta.head(wanted);
        if (!out.converged) return out;  // refused by the caller: no Ritz vectors needed
        out.Y.resize(n, wanted);
        advise_huge_pages(out.Y);
        out.Y.noalias() = V.leftCols(k) * S.leftCols(wanted);
        return out;
      }
    }
    if (k + b > V.cols()) {
      const Eigen::Index cols = std::min<Eigen::Index>(max_dim, 2 * V.cols());
      V.conservativeResize(n, cols);
      advise_huge_pages(V);
      T.conservativeResizeLike(Eigen::MatrixXd::Zero(cols, cols));
    }
    V.middleCols(k, b) = W;
    T.block(k, j0, b, b) = R;
    T.block(j0, k, b, b) = R.transpose();
  }
}

// Shift-invert Lanczos over the sparse factor: the lowest eigenpairs of K v = lambda M v, as
// many as o.modes asks (plus the six rigid ones) or all below o.max_frequency.
void iterative_modes(const SparseMatrix& K, const SparseMatrix& M, const EigenOptions& o,
                     const std::function<void(const std::string&)>& status, EigenResult& r,
                     Eigen::VectorXd& evals, Eigen::MatrixXd& evecs) {
  const Eigen::Index n = K.rows();
  const double two_pi = 2 * std::numbers::pi;
  double sigma = -std::pow(two_pi * o.shift_hz, 2);
  const double lambda_max = std::pow(two_pi * o.max_frequency, 2);
  r.factorization = kFactorName;
  auto t0 = std::chrono::steady_clock::now();
  SplitShiftInvert op(K, M);
  const Eigen::Index max_nev = std::min<Eigen::Index>(n - 2, Eigen::Index(o.mode_cap) + 6);
  Eigen::Index nev = o.modes > 0 ? Eigen::Index(o.modes) + 6 : std::min<Eigen::Index>(32, max_nev);
  if (o.modes > 0 && nev > max_nev)
    throw InputError("asked for " + std::to_string(o.modes) + " modes but the mesh has only " +
                     std::to_string(n) + " degrees of freedom (or the cap " +
                     std::to_string(o.mode_cap) + " is lower)");
  const FactorEstimate est = op.analyze(o.node_ordering);
  r.factor_entries = est.entries, r.factor_bytes = est.bytes, r.factor_flops = est.flops;
  const double entries = double(K.nonZeros());
  r.matrix_bytes = kFactorizingBytesPerEntry * entries;
  bool by_memory = false;
  const Eigen::Index max_dim = lanczos_dim(n, iteration_reserve(n, est, entries, o), o, &by_memory);
  r.basis_bytes = 8.0 * double(n) *
                  double(o.method == EigenOptions::Method::BlockLanczos
                             ? max_dim
                             : std::min<Eigen::Index>(n, 2 * nev + 1));
  if (est.flops > 0) r.factor_seconds_estimate = est.flops / (kSupernodalEfficiency * blas_rate());
  if (status && est.bytes > 0) {
    char secs[48];
    std::snprintf(secs, sizeof secs, ", roughly %.2g s at %.0f GFLOP/s dense",
                  r.factor_seconds_estimate, blas_rate() / 1e9);
    status("factor: " + gigabytes(est.bytes) + " (nnz(L) " +
           std::to_string(std::llround(est.entries)) + ", " +
           std::to_string(std::llround(est.flops / 1e9)) + " GFLOP" + secs + ")");
  }
  check_budget(n, est, entries, o, "");
  // Round-off on a badly shaped mesh can make K - sigma M indefinite along the rigid motions
  // when |sigma| is tiny next to K's scale: move the shift further down and retry.
  for (int attempt = 0;; ++attempt) {
    try {
      op.factor(sigma);
      break;
    } catch (const InputError&) {
      if (attempt == 4) throw;
      sigma *= 100;
      if (status) status("factorization failed; retrying with shift " + std::to_string(sigma));
    }
  }
  r.shift = sigma;
  r.factor_seconds = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  if (o.method == EigenOptions::Method::BlockLanczos) {
    // The first `nev`, but none above max_frequency: precompute drops those, and where the
    // N-th mode lies far above the band (a bar's 100th at 80 kHz), finding them would cost most
    // of the solve.
    const double theta_min = 1.0 / (lambda_max - sigma);
    const double theta_low =
        o.modes > 0 && o.min_frequency > 0 ? 1.0 / (band_bottom(o) - sigma) : INFINITY;
    BlockLanczosResult bl =
        block_lanczos(op, theta_min, theta_low, o.modes > 0 ? nev : max_nev, o.modes > 0 ? nev : 0,
                      o.tolerance, max_dim, o.block, status);
    r.solves = 1;
    r.operations = bl.applied;
    // Unconverged Ritz pairs would be wrong modes. Where the budget set the basis, this is a
    // refusal for memory, as the budget check's is.
    if (!bl.converged && !by_memory)
      throw InternalError("block Lanczos did not converge " + std::to_string(bl.theta.size()) +
                          " modes within " + std::to_string(max_dim) + " vectors");
    if (!bl.converged)
      throw BudgetError("the Lanczos basis the memory budget leaves (" + std::to_string(max_dim) +
                        " vectors, " + gigabytes(r.basis_bytes) + ") converged " +
                        std::to_string(bl.done) + " of the " + std::to_string(bl.theta.size()) +
                        (o.modes > 0 ? " modes asked for" : " modes found below --max-freq") +
                        ": lower --max-freq or --max-modes, raise --max-tet-volume (coarser "
                        "elements), or raise --max-memory");
    r.capped = bl.capped && o.modes == 0;  // N modes asked for: stopping at N is no cap
    evals = (1.0 / bl.theta.array() + sigma).matrix();
    evecs = std::move(bl.Y);
  } else {
    for (;;) {
      const Eigen::Index ncv =
          std::min<Eigen::Index>(n, std::max<Eigen::Index>(2 * nev + 1, nev + 20));
      if (status)
        status("Lanczos for " + std::to_string(nev) + " modes (" + std::to_string(ncv) +
               " vectors)");
      Spectra::SymEigsSolver<SplitShiftInvert> eigs(op, nev, ncv);
      eigs.init();
      eigs.compute(Spectra::SortRule::LargestAlge, 1000, o.tolerance,
                   Spectra::SortRule::LargestAlge);
      ++r.solves;
      r.operations += eigs.num_operations();
      if (eigs.info() != Spectra::CompInfo::Successful)
        throw InternalError("the eigen-solver did not converge for " + std::to_string(nev) +
                            " modes");
      // theta = 1 / (lambda - sigma), largest first: lambda ascending.
      evals = (1.0 / eigs.eigenvalues().array() + sigma).matrix();
      evecs = eigs.eigenvectors();
      if (o.modes > 0) {  // again with room for the modes below the band, if it had some
        const auto below = Eigen::Index((evals.array() < band_bottom(o)).count());
        const Eigen::Index want =
            std::min(max_nev, Eigen::Index(o.modes) +
                                  std::clamp<Eigen::Index>(below, 6, Eigen::Index(o.modes) + 6));
        if (want <= nev || evals(evals.size() - 1) >= lambda_max) break;
        nev = want;
        continue;
      }
      if (evals(evals.size() - 1) >= lambda_max) break;
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
  }
  r.lanczos_seconds = seconds_since(t0);
  r.solve_seconds = op.solve_seconds;

  // Back to the original problem in one multi-right-hand-side solve.
  op.to_modes(evecs);
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
  const double lambda_max = std::pow(two_pi * o.max_frequency, 2);
  const double lambda_min = band_bottom(o);

  EigenResult r;
  Eigen::VectorXd evals;
  Eigen::MatrixXd evecs;
  // Fewer modes than asked for is a refusal only where the mesh has fewer. The iterative
  // solvers refuse that before they start, so from them fewer means the band ended; the dense
  // one finds every mode, so there it ended where one lies above it.
  bool band_ended = n > kDenseDofs;
  if (n <= kDenseDofs) {
    const auto t0 = std::chrono::steady_clock::now();
    dense_modes(K, M, evals, evecs);
    r.factorization = "dense (Eigen, all modes)";
    r.solves = 1;
    r.lanczos_seconds = seconds_since(t0);
  } else {
    iterative_modes(K, M, o, status, r, evals, evecs);
  }

  // M-orthonormal basis of the rigid motions: Q = R L^-T with L L^T = R^T M R.
  const Eigen::MatrixXd MR = M * rigid;
  const Eigen::MatrixXd G = rigid.transpose() * MR;
  const Eigen::LLT<Eigen::MatrixXd> llt(G);
  if (llt.info() != Eigen::Success) throw InternalError("rigid-body motions are degenerate");
  const Eigen::MatrixXd MQ = llt.matrixL().solve(MR.transpose()).transpose();  // M Q

  // M-normalize, and classify rigid modes by their M-weighted overlap with the rigid motions.
  Eigen::MatrixXd Mv;
  symmetric_product(M, evecs, Mv);
  std::vector<Eigen::Index> elastic;
  for (Eigen::Index j = 0; j < evals.size(); ++j) {
    const double mnorm = std::sqrt(evecs.col(j).dot(Mv.col(j)));
    evecs.col(j) /= mnorm;
    Mv.col(j) /= mnorm;
    const double overlap = (MQ.transpose() * evecs.col(j)).norm();
    if (overlap > 0.5) {
      ++r.rigid_removed;
      r.rigid_lambda.push_back(evals(j));
    } else {
      elastic.push_back(j);
    }
  }
  if (r.rigid_removed != 6) {
    std::string hz;
    for (double l : r.rigid_lambda) {
      char buf[32];
      std::snprintf(buf, sizeof buf, " %.6g", std::sqrt(std::abs(l)) / two_pi);
      hz += buf;
    }
    throw InputError("found " + std::to_string(r.rigid_removed) +
                     " modes that move the body almost rigidly instead of 6 (at" + hz +
                     " Hz): the solid is not one well-connected piece (parts joined only at an "
                     "edge or a vertex, or slivers from a poor surface)");
  }
  std::size_t in_band = 0;  // those at or above min_frequency, which count toward o.modes
  for (Eigen::Index j : elastic) {
    if (evals(j) > lambda_max) {  // none above the band, however many were asked for
      band_ended = true;
      break;
    }
    if (o.modes > 0 && in_band == o.modes) break;
    if (o.modes == 0 && r.lambda.size() == o.mode_cap) {
      r.capped = true;
      break;
    }
    r.lambda.push_back(evals(j));
    in_band += evals(j) >= lambda_min;
  }
  if (o.modes > 0 && r.lambda.size() < o.modes && !band_ended)
    throw InputError("asked for " + std::to_string(o.modes) + " modes, but the mesh (" +
                     std::to_string(n) + " degrees of freedom) has only " +
                     std::to_string(r.lambda.size()) +
                     " elastic modes: ask for fewer (--max-modes) or use smaller elements "
                     "(--max-tet-volume)");
  r.vectors.resize(n, Eigen::Index(r.lambda.size()));
  Eigen::MatrixXd Mk(n, r.vectors.cols());
  advise_huge_pages(r.vectors);
  advise_huge_pages(Mk);
  for (std::size_t i = 0; i < r.lambda.size(); ++i) {
    r.vectors.col(Eigen::Index(i)) = evecs.col(elastic[i]);
    Mk.col(Eigen::Index(i)) = Mv.col(elastic[i]);
  }
  evecs.resize(0, 0);
  Mv.resize(0, 0);
  Eigen::MatrixXd Kv;
  symmetric_product(K, r.vectors, Kv);
  for (std::size_t i = 0; i < r.lambda.size(); ++i) {
    const auto c = Eigen::Index(i);
    r.residual.push_back((Kv.col(c) - r.lambda[i] * Mk.col(c)).norm() / Kv.col(c).norm());
  }
  return r;
}

}  // namespace chladni::precompute
