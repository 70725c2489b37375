// Spectra + sparse Cholesky: the only unit that includes them.
#include "chladni/precompute/eigensolve.hpp"

#include <Spectra/SymEigsSolver.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <random>

#include "chladni/core/error.hpp"
#include "eigensolve_dense.hpp"
#include "huge_pages.hpp"
#include "shift_invert.hpp"
#include "timing.hpp"

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

// Block Lanczos with full reorthogonalization on C (symmetric, eigenvalues theta > 0), for the
// largest theta: the `want` largest, or (want = 0) all above theta_min, at most `cap`. Spectra's
// Lanczos is single-vector; applying C to blocks of vectors turns the triangular solves and the
// mass product, which dominate, from matrix-vector into matrix-matrix work (about 4x faster here).
struct BlockLanczosResult {
  Eigen::VectorXd theta;  ///< descending
  Eigen::MatrixXd Y;      ///< Ritz vectors (orthonormal)
  std::size_t applied = 0;
  Eigen::Index done = 0;  ///< converged pairs among theta
  bool converged = false;
  bool capped = false;  ///< `cap` pairs found and the band goes on
};

BlockLanczosResult block_lanczos(const SplitShiftInvert& op, Eigen::Index want, double theta_min,
                                 Eigen::Index cap, double tol, Eigen::Index max_dim, Eigen::Index b,
                                 const std::function<void(const std::string&)>& status) {
  const Eigen::Index n = op.rows();
  max_dim = std::min<Eigen::Index>(max_dim, n) / b * b;
  Eigen::MatrixXd V(
      n, std::min<Eigen::Index>(max_dim, std::max<Eigen::Index>(4 * b, 4 * want + 2 * b)));
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
  for (Eigen::Index k = b;; k += b) {  // V[:, 0:k] holds the basis
    const Eigen::Index j0 = k - b;
    op.apply_block(V.middleCols(j0, b), W);
    out.applied += std::size_t(b);
    const Eigen::MatrixXd A = V.middleCols(j0, b).transpose() * W;
    T.block(j0, j0, b, b) = 0.5 * (A + A.transpose());
    // The three-term recurrence: W = C V_j - V_j A_j - V_{j-1} B_{j-1}^T.
    W.noalias() -= V.middleCols(j0, b) * T.block(j0, j0, b, b);
    if (j0 >= b) W.noalias() -= V.middleCols(j0 - b, b) * T.block(j0 - b, j0, b, b);
    // Ritz pairs of the current projection; residual of pair i is ||B_next S(last block, i)||,
    // with B_next from the next orthonormalization.
    const bool full = k + b > max_dim;
    orthonormalize(W, k, R);
    es.compute(T.topLeftCorner(k, k));
    const Eigen::VectorXd theta = es.eigenvalues().reverse();
    const Eigen::MatrixXd S = es.eigenvectors().rowwise().reverse();
    const Eigen::VectorXd res = (R * S.bottomRows(b)).colwise().norm();
    Eigen::Index wanted = 0, done = 0;
    for (Eigen::Index i = 0; i < k; ++i) {
      const bool in = want > 0 ? i < want : theta(i) >= theta_min && i < cap;
      if (!in) break;
      ++wanted;
      done += res(i) <= tol * theta(i);
    }
    // By threshold: also require the first Ritz value below it to be converged, so that no
    // unconverged one can still rise above it (at the cap, the `cap` largest are wanted, as by
    // count); and a basis well past the wanted count, so that a multiplet wider than the block
    // has had room to appear.
    const bool bracketed =
        (want > 0 || wanted == cap || (wanted < k && res(wanted) <= tol * theta(wanted))) &&
        k >= wanted + 2 * b;
    if (status && (k / b) % 8 == 0)
      status("block Lanczos: " + std::to_string(k) + " vectors, " + std::to_string(done) + " of " +
             std::to_string(wanted) + " wanted modes converged");
    if ((wanted > 0 && done == wanted && bracketed && (want == 0 || wanted == want)) || full) {
      out.converged = done == wanted && bracketed;
      out.done = done;
      out.capped = want == 0 && wanted == cap && wanted < k && theta(wanted) >= theta_min;
      out.theta = theta.head(wanted);
      if (!out.converged) return out;  // refused by the caller: no Ritz vectors needed
      out.Y.resize(n, wanted);
      advise_huge_pages(out.Y);
      out.Y.noalias() = V.leftCols(k) * S.leftCols(wanted);
      return out;
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

std::string gigabytes(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f GB", bytes / 1e9);
  return buf;
}

// The eigen-solve's memory has two peaks besides the factor. Factorizing: K (a double and an int
// per entry), M (the same for a third of the entries), the upper triangle of K - sigma M in long
// indices (a double and a long for half the entries) and CHOLMOD's permuted copy of it (the
// same): 32 bytes per entry of K. Iterating: K, M and the kept pattern (20 bytes per entry), the
// Lanczos basis and the Ritz vectors (the modes).
constexpr double kFactorizingBytesPerEntry = 12 + 4 + 8 + 8;
constexpr double kIteratingBytesPerEntry = 12 + 4 + 4;

// The modes the Lanczos run must hold, the six rigid ones included: those asked for, or those
// expected below max_frequency within the cap; 0 where unknown (a band of unknown size).
Eigen::Index ritz_columns(Eigen::Index n, const EigenOptions& o) {
  const std::size_t modes = o.modes > 0 ? o.modes : std::min(o.expected_modes, o.mode_cap);
  return modes == 0 ? 0 : std::min<Eigen::Index>(n, Eigen::Index(modes) + 6);
}

// The smallest basis worth factorizing for: modes converge in about 3.3 vectors per mode (352
// for spot.obj's 106), so 4 per mode and two blocks.
Eigen::Index lanczos_floor(Eigen::Index n, const EigenOptions& o) {
  const Eigen::Index ritz = ritz_columns(n, o);
  return std::min<Eigen::Index>(n, ritz > 0 ? 4 * ritz + 2 * o.block : 4 * o.block);
}

// The largest basis: twice the floor for the cap's modes (clusters of close modes, a cube's or
// a box's, can take 6 vectors per mode where they are few), where the budget leaves room for it
// after the factor, the matrices and the Ritz vectors (`reserved`), but never below the floor
// (the budget check refuses that case). `by_memory` says whether the budget, not the count, set
// it. The basis grows only as the iteration needs it.
Eigen::Index lanczos_dim(Eigen::Index n, double reserved, const EigenOptions& o,
                         bool* by_memory = nullptr) {
  const Eigen::Index max_nev = std::min<Eigen::Index>(n - 2, Eigen::Index(o.mode_cap) + 6);
  const Eigen::Index target = std::min<Eigen::Index>(n, 8 * max_nev + 4 * o.block);
  Eigen::Index dim = target;
  if (o.max_memory > 0)
    dim = std::min<Eigen::Index>(
        dim, Eigen::Index(std::max(0.0, o.max_memory - reserved) / (8.0 * double(n))));
  if (by_memory) *by_memory = dim < target;
  return std::max(dim, lanczos_floor(n, o));
}

// What the eigen-solve needs at most: the factor with whichever phase is larger. Refuses
// (BudgetError) above the budget, with the parts.
double check_budget(Eigen::Index n, const FactorEstimate& est, double entries,
                    const EigenOptions& o, const std::string& how, const char* amount = "about ") {
  const double factorizing = kFactorizingBytesPerEntry * entries;
  const double basis = 8.0 * double(n) * double(lanczos_floor(n, o) + ritz_columns(n, o));
  const double iterating = kIteratingBytesPerEntry * entries + basis;
  const double need = est.bytes + std::max(factorizing, iterating);
  if (o.max_memory <= 0 || need <= o.max_memory) return need;
  throw BudgetError(
      "the eigen-solve would need " + std::string(amount) + gigabytes(need) +
      " (the sparse factor of K - sigma M for " + std::to_string(n) +
      " DOFs: " + gigabytes(est.bytes) + ", nnz(L) " + std::to_string(std::llround(est.entries)) +
      ", " + std::to_string(std::llround(est.flops / 1e9)) +
      " GFLOP; the matrices and their copies while it is computed: " + gigabytes(factorizing) +
      "; afterwards the matrices, the Lanczos basis and the modes: " + gigabytes(iterating) + how +
      "), more than the memory budget of " + gigabytes(o.max_memory) +
      ": raise --max-tet-volume (coarser elements), lower --max-freq or "
      "--max-modes, or raise --max-memory");
}

// The bytes the iteration may count on before the basis: the factor, the matrices and the
// Ritz vectors.
double iteration_reserve(Eigen::Index n, const FactorEstimate& est, double entries,
                         const EigenOptions& o) {
  return est.bytes + kIteratingBytesPerEntry * entries + 8.0 * double(n) * ritz_columns(n, o);
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
    const double theta_min = 1.0 / (lambda_max - sigma);
    BlockLanczosResult bl = block_lanczos(op, o.modes > 0 ? nev : 0, theta_min, max_nev,
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
    r.capped = bl.capped;
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
  }
  r.lanczos_seconds = seconds_since(t0);
  r.solve_seconds = op.solve_seconds;

  // Back to the original problem in one multi-right-hand-side solve.
  op.to_modes(evecs);
}

}  // namespace

double default_memory_budget() {
  // MemAvailable counts what can be had without swapping (free plus reclaimable caches).
  std::ifstream in("/proc/meminfo");
  for (std::string line; std::getline(in, line);) {
    double kb = 0;
    if (std::sscanf(line.c_str(), "MemAvailable: %lf kB", &kb) == 1) return 0.8 * kb * 1024.0;
  }
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? 0.8 * double(pages) * double(size) : 0.0;
}

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

  EigenResult r;
  Eigen::VectorXd evals;
  Eigen::MatrixXd evecs;
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
  for (Eigen::Index j : elastic) {
    if (o.modes == 0 && evals(j) > lambda_max) break;
    if (o.modes > 0 && r.lambda.size() == o.modes) break;
    if (o.modes == 0 && r.lambda.size() == o.mode_cap) {
      r.capped = true;
      break;
    }
    r.lambda.push_back(evals(j));
  }
  if (o.modes > 0 && r.lambda.size() < o.modes)
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

namespace {

// CHOLMOD's analysis of the node graph, where each element couples all its nodes. K's pattern is
// this graph with each entry a 3 x 3 block, so its factor has 9 times the entries and 27 times
// the flops. `entries` receives the entries of K.
FactorEstimate node_graph_estimate(const FemMesh& mesh, double& entries,
                                   std::vector<std::int64_t>* ordering = nullptr) {
  const int npe = mesh.nodes_per_element();
  std::vector<Eigen::Triplet<double, int>> t;
  t.reserve(mesh.element_count() * std::size_t(npe * npe));
  advise_huge_pages(t.data(), sizeof(t[0]) * t.capacity());
  for (std::size_t e = 0; e < mesh.element_count(); ++e)
    for (int a = 0; a < npe; ++a)
      for (int b = 0; b < npe; ++b)
        t.emplace_back(int(mesh.elements[e * npe + a]), int(mesh.elements[e * npe + b]),
                       a == b ? 1.0 : 0.0);
  SparseMatrix G(Eigen::Index(mesh.nodes.size()), Eigen::Index(mesh.nodes.size()));
  G.setFromTriplets(t.begin(), t.end());
  G.makeCompressed();
  t = {};
  Factor f;
  FactorEstimate est = f.analyze(G, 1, nullptr);
  if (ordering) *ordering = f.ordering();
  est.entries *= 9, est.bytes *= 9, est.flops *= 27;
  entries = 9.0 * double(G.nonZeros());
  return est;
}

}  // namespace

double check_eigen_memory(const FemMesh& mesh, const EigenOptions& o,
                          std::vector<std::int64_t>* node_ordering) {
  if (o.max_memory <= 0) return 0;
  double entries = 0;
  const FactorEstimate est = node_graph_estimate(mesh, entries, node_ordering);
  if (est.bytes <= 0) return 0;  // this build's factorization cannot say before factorizing
  return check_budget(Eigen::Index(mesh.dofs()), est, entries, o,
                      "; estimated from the mesh before assembly");
}

double check_eigen_memory_before_meshing(const FemMesh& coarse, const FemMesh& sample,
                                         double tetrahedra, const EigenOptions& o) {
  if (o.max_memory <= 0) return 0;
  // DOFs per tetrahedron, at most what a large quality mesh has (P2: 1.32 nodes per tetrahedron
  // from Euler's formula with about 6.3 tetrahedra per vertex, so 3.95 DOFs; P1: 0.48) and never
  // above the sample's own, where the surface's share is larger.
  const double ns = double(sample.dofs());
  const bool p2 = sample.nodes_per_element() == 10;
  const double n =
      std::max(ns, std::min(p2 ? 3.6 : 0.4, ns / double(sample.element_count())) * tetrahedra);
  double entries = 0;
  FactorEstimate est = node_graph_estimate(sample, entries);
  if (est.bytes <= 0) return 0;
  // Nested dissection's factor grows as n^(4/3) in a solid and n log n in a shell, and a thin
  // part grows faster once its thickness is resolved: the growth between the two meshes,
  // within [1, 4/3] (flops [1, 2]), extrapolated from the finer one can only underestimate.
  // Where the two are alike (a surface that decides the mesh), only the floors are known.
  const double r = std::log(n / ns), rs = std::log(ns / double(coarse.dofs()));
  double a = 1, af = 1;
  if (rs > 0.05) {
    double unused = 0;
    const FactorEstimate low = node_graph_estimate(coarse, unused);
    a = std::clamp(std::log(est.entries / low.entries) / rs, 1.0, 4.0 / 3.0);
    af = std::clamp(std::log(est.flops / low.flops) / rs, 1.0, 2.0);
  }
  est.entries *= std::exp(a * r), est.bytes *= std::exp(a * r), est.flops *= std::exp(af * r);
  entries *= n / ns;
  return check_budget(Eigen::Index(n), est, entries, o,
                      "; a lower bound found before meshing, from meshes of " +
                          std::to_string(coarse.element_count()) + " and " +
                          std::to_string(sample.element_count()) + " tetrahedra extrapolated to " +
                          std::to_string(std::llround(tetrahedra)),
                      "at least ");
}

}  // namespace chladni::precompute
