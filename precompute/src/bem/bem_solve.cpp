// Assembly of the Burton-Miller system and its solution: LAPACK's LU (zgetrf/zgetrs through the
// BLAS) for small systems, restarted GMRES preconditioned by the LU of a nearby frequency for
// large ones.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <numbers>
#include <string>

#include "../parallel.hpp"
#include "../timing.hpp"
#include "bem_gmres.hpp"
#include "bem_hmatrix.hpp"
#include "bem_kernels.hpp"
#include "bem_near.hpp"
#include "chladni/core/error.hpp"
#include "chladni/precompute/bem.hpp"

extern "C" {
void zgetrf_(const int* m, const int* n, double* a, const int* lda, int* ipiv, int* info);
void zgetrs_(const char* trans, const int* n, const int* nrhs, const double* a, const int* lda,
             const int* ipiv, double* b, const int* ldb, int* info);
void zgemv_(const char* trans, const int* m, const int* n, const double* alpha, const double* a,
            const int* lda, const double* x, const int* incx, const double* beta, double* y,
            const int* incy);
void cgetrf_(const int* m, const int* n, float* a, const int* lda, int* ipiv, int* info);
void cgetrs_(const char* trans, const int* n, const int* nrhs, const float* a, const int* lda,
             const int* ipiv, float* b, const int* ldb, int* info);
}

namespace chladni::precompute {
namespace {

using namespace bem_detail;

// Debian 12's OpenBLAS level-2 complex kernels read a little past their operands (OpenBLAS
// #4013): every buffer handed to LAPACK carries this many spare entries.
constexpr std::size_t kPad = 64;

}  // namespace

BemSolver::NearCache::NearCache(const BemMesh& m, const BemOptions& o)
    : rows(m.elements()), static_sum(m.elements()), far(m) {
  const std::size_t n = m.elements();
  parallel_for(n, o.threads, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t i = r0; i < r1; ++i) {
      const Vec3 &x = m.centroid[i], &nx = m.normal[i];
      double sum = 0;
      for (std::size_t j = 0; j < n; ++j) {
        if (j == i) continue;
        const double d2 = dot(sub(x, m.centroid[j]), sub(x, m.centroid[j]));
        const double far = o.far_ratio * m.size[j];
        if (d2 > far * far) {
          cd acc[5] = {0, 0, 0, 0, 0};
          add_kernels(x, nx, m.centroid[j], m.normal[j], 0.0, m.area[j], acc);
          sum += acc[4].real();
        } else {
          const ElementIntegrals e = element_integrals(m, uint32_t(j), x, nx, 0.0, o);
          cd one[5] = {0, 0, 0, 0, 0};
          add_kernels(x, nx, m.centroid[j], m.normal[j], 0.0, m.area[j], one);
          const double near = o.near_ratio * m.size[j];
          rows[i].push_back({uint32_t(j), d2 < near * near, e.single.real() - one[0].real(),
                             e.dbl.real() - one[1].real(), e.adjoint.real() - one[2].real(),
                             e.hyper_static - one[3].real()});
          sum += e.hyper_static;
        }
      }
      static_sum[i] = sum;
    }
  });
}

namespace bem_detail {

SelfTerms self_terms(const BemMesh& m, const BemSolver::NearCache& cache, double k, cd alpha,
                     const BemOptions& o, std::size_t i) {
  const ElementIntegrals self = element_integrals(m, uint32_t(i), m.centroid[i], m.normal[i], k, o);
  return {0.5 - alpha * (self.hyper - self.hyper_static - cache.static_sum[i]), self.single};
}

}  // namespace bem_detail

namespace {

// Row i of A (into `row`, which holds the centroid-rule entries with a 0 diagonal) and b_i of
// every right-hand side, given the far parts of their sums sum_(j != i) (S + a K')_j q_j in
// b_i: the near elements get their corrections, the diagonal the self term.
void finish_row(const BemMesh& m, const BemSolver::NearCache& cache, double k, cd alpha,
                std::span<const std::vector<cd>> qs, const BemOptions& o, std::size_t i,
                std::vector<std::vector<cd>>& bs, cd* row) {
  const std::size_t count = qs.size();
  for (std::size_t v = 0; v < count; ++v) bs[v][i] = -0.5 * alpha * qs[v][i] - bs[v][i];
  near_row(m, cache, k, alpha, i, [&](uint32_t j, cd da, cd db) {
    row[j] += da;
    for (std::size_t v = 0; v < count; ++v) bs[v][i] -= db * qs[v][j];
  });
  const SelfTerms self = self_terms(m, cache, k, alpha, o, i);
  row[i] = self.a;
  for (std::size_t v = 0; v < count; ++v) bs[v][i] -= self.b * qs[v][i];
}

// Row-major A (A[i * n + j]: collocation point i, element j) and bs[v] = B qs[v]: every row
// first by the centroid rule (far_row, or the device's rows), then finish_row.
void assemble(const BemMesh& m, const BemSolver::NearCache& cache, BemGpuRows* gpu, double k,
              std::span<const std::vector<cd>> qs, const BemOptions& o, std::vector<cd>& A,
              std::vector<std::vector<cd>>& bs) {
  const std::size_t n = m.elements(), count = qs.size();
  // Every entry is written below: reuse the buffer rather than zero-filling (and page-faulting)
  // hundreds of megabytes per frequency.
  if (A.size() != n * n + kPad) A.assign(n * n + kPad, cd(0.0));
  bs.assign(count, std::vector<cd>(n, cd(0.0)));
  const cd alpha = coupling(m, k, o);
  if (gpu) {  // centroid-rule rows on the device, block by block; the rest on the CPU
    // The device sums the first right-hand side; any others are summed here.
    const SplitRightHandSides more_qs(qs, 1);
    std::vector<std::complex<float>> entries, rhs;
    for (std::size_t r0 = 0; r0 < n; r0 += gpu->block_rows()) {
      const std::size_t rows = std::min(gpu->block_rows(), n - r0);
      gpu->rows(k, alpha.imag(), qs[0], r0, rows, entries, rhs);
      parallel_for(rows, o.threads, [&](std::size_t a, std::size_t e) {
        std::vector<cd> more(count);
        for (std::size_t r = a; r < e; ++r) {
          const std::size_t i = r0 + r;
          cd* row = A.data() + i * n;
          for (std::size_t j = 0; j < n; ++j) row[j] = cd(entries[r * n + j]);
          bs[0][i] = cd(rhs[r]);
          if (count > 1)
            far_rhs(cache.far, m.centroid[i], m.normal[i], k, alpha.imag(), more_qs.pre,
                    more_qs.pim, i, more.data());
          for (std::size_t v = 1; v < count; ++v) bs[v][i] = more[v - 1];
          finish_row(m, cache, k, alpha, qs, o, i, bs, row);
        }
      });
    }
    return;
  }
  parallel_for(n, o.threads, [&](std::size_t r0, std::size_t r1) {
    std::vector<double> rre(n), rim(n), tre(n), tim(n);
    for (std::size_t i = r0; i < r1; ++i) {
      far_row(cache.far, m.centroid[i], m.normal[i], k, alpha.imag(), rre.data(), rim.data(),
              tre.data(), tim.data());
      rre[i] = rim[i] = tre[i] = tim[i] = 0;  // the self term is the closed form
      cd* row = A.data() + i * n;
      for (std::size_t j = 0; j < n; ++j) row[j] = cd(rre[j], rim[j]);
      for (std::size_t v = 0; v < count; ++v) {
        cd far_rhs = 0;
        for (std::size_t j = 0; j < n; ++j) far_rhs += cd(tre[j], tim[j]) * qs[v][j];
        bs[v][i] = far_rhs;
      }
      finish_row(m, cache, k, alpha, qs, o, i, bs, row);
    }
  });
}

// y = A x by the BLAS (zgemv on A^T, column-major: the transposed kernel, memory-bound and
// threaded). x is copied into a padded buffer for the over-reading kernels noted above.
void matvec(const std::vector<cd>& A, std::size_t n, const cd* x, cd* y) {
  std::vector<cd> xp(x, x + n);
  xp.resize(n + kPad);
  const char trans = 'T';
  const int nn = int(n), one = 1;
  const cd alpha = 1.0, beta = 0.0;
  zgemv_(&trans, &nn, &nn, reinterpret_cast<const double*>(&alpha),
         reinterpret_cast<const double*>(A.data()), &nn, reinterpret_cast<const double*>(xp.data()),
         &one, reinterpret_cast<const double*>(&beta), reinterpret_cast<double*>(y), &one);
}

}  // namespace

// LU factors of A^T in column-major order, i.e. of the row-major A as LAPACK sees it; solves
// with A use getrs's transposed mode. Double precision for direct solves; single precision (half
// the memory traffic, about twice the speed) when the factors only precondition GMRES, which
// restores double-precision residuals in a few iterations.
struct BemSolver::Lu {
  int n = 0;
  bool single = false;
  double k = 0;  // the frequency factorized
  std::vector<cd> factors;
  std::vector<std::complex<float>> factors32;
  std::vector<int> pivots;
  bool factor(const std::vector<cd>& a, std::size_t size, bool in_single) {
    n = int(size);
    single = in_single;
    pivots.assign(size + kPad, 0);
    int info = 0;
    if (single) {
      factors.clear();
      factors32.assign(a.begin(), a.end());
      cgetrf_(&n, &n, reinterpret_cast<float*>(factors32.data()), &n, pivots.data(), &info);
    } else {
      factors32.clear();
      factors = a;
      zgetrf_(&n, &n, reinterpret_cast<double*>(factors.data()), &n, pivots.data(), &info);
    }
    return info == 0;
  }
  void solve(cd* x) const {
    const char trans = 'T';
    const int one = 1;
    int info = 0;
    if (single) {
      std::vector<std::complex<float>> y(x, x + n);
      y.resize(std::size_t(n) + kPad);
      cgetrs_(&trans, &n, &one, reinterpret_cast<const float*>(factors32.data()), &n, pivots.data(),
              reinterpret_cast<float*>(y.data()), &n, &info);
      for (int i = 0; i < n; ++i) x[i] = cd(y[std::size_t(i)]);
    } else {
      zgetrs_(&trans, &n, &one, reinterpret_cast<const double*>(factors.data()), &n, pivots.data(),
              reinterpret_cast<double*>(x), &n, &info);
    }
  }
};

namespace {

double relative_residual(const MatVec& apply, const std::vector<cd>& b, const std::vector<cd>& x) {
  const std::size_t n = b.size();
  std::vector<cd> ax(n + kPad);
  apply(x.data(), ax.data());
  for (std::size_t i = 0; i < n; ++i) ax[i] -= b[i];
  ax.resize(n);
  return norm2(ax) / norm2(b);
}

// Throws on a non-finite b; for b = 0 sets the zero pressure and returns true.
bool zero_right_hand_side(const std::vector<cd>& b, BemSolver::Result& res) {
  const double nb = norm2(b);
  if (!std::isfinite(nb)) throw InternalError("bem: the right-hand side is not finite");
  if (nb > 0) return false;
  res.pressure.assign(b.size(), cd(0.0));
  return true;
}

// GMRES preconditioned by the factors of the last factorized frequency (factor_k(): NaN when
// there are none). Factors of a frequency within 1 / extent precondition GMRES in under ~40
// iterations (the phase of e^(ikR) across the object moves by less than 1 rad; on the bowl at
// 3 kHz, 21 iterations at 0.7 rad, 39 at 1.4, no convergence in 60 at 2.1); farther ones are not
// worth trying: factorize here first. If GMRES fails with older factors, factorize here and
// solve again. Returns the seconds spent iterating; x holds n + pad entries.
double gmres_with_nearby_factors(double k, double extent, const BemOptions& o,
                                 const std::function<double()>& factor_k,
                                 const std::function<void()>& factorize, const MatVec& apply,
                                 const Precondition& precondition, const std::vector<cd>& b,
                                 std::size_t pad, BemSolver::Result& res, std::vector<cd>& x) {
  if (!(std::abs(k - factor_k()) * extent <= o.refactor_phase)) factorize();
  auto t0 = std::chrono::steady_clock::now();
  res.iterations = gmres(apply, precondition, b, o, pad, x);
  res.residual = relative_residual(apply, b, x);
  double seconds = seconds_since(t0);
  if (!(res.residual <= 10 * o.gmres_tolerance) && factor_k() != k) {
    factorize();
    t0 = std::chrono::steady_clock::now();
    std::fill(x.begin(), x.end(), cd(0.0));
    res.iterations += gmres(apply, precondition, b, o, pad, x);
    res.residual = relative_residual(apply, b, x);
    seconds += seconds_since(t0);
  }
  return seconds;
}

void check_converged(const BemSolver::Result& res, const BemOptions& o) {
  if (!(res.residual <= 10 * o.gmres_tolerance))
    throw InternalError("bem: the solve did not converge (relative residual " +
                        std::to_string(res.residual) + " after " + std::to_string(res.iterations) +
                        " GMRES iterations)");
}

}  // namespace

BemSolver::BemSolver(const BemMesh& mesh, const BemOptions& options)
    : mesh_(mesh), options_(options) {
  options_.validate();
  if (mesh.elements() < 4) throw InputError("bem: the surface needs at least 4 triangles");
  Vec3 lo = mesh.vertices[0], hi = lo;
  for (const Vec3& v : mesh.vertices)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v[c]), hi[c] = std::max(hi[c], v[c]);
  extent_ = norm(sub(hi, lo));
}

BemSolver::BemSolver(const BemMesh& mesh, const BemOptions& options,
                     std::shared_ptr<const NearCache> near)
    : BemSolver(mesh, options) {
  if (near && near->rows.size() != mesh.elements())
    throw InternalError("bem: a shared near field of another mesh");
  near_ = std::move(near);
}

BemSolver::~BemSolver() = default;

std::shared_ptr<const BemSolver::NearCache> BemSolver::near_field() {
  if (!near_) {
    const auto t0 = std::chrono::steady_clock::now();
    near_ = std::make_shared<const NearCache>(mesh_, options_);
    times_.assembly += seconds_since(t0);
  }
  return near_;
}

BemSolver::Result BemSolver::solve(double k, std::span<const cd> q) {
  const std::vector<cd> one(q.begin(), q.end());
  return std::move(solve(k, std::span<const std::vector<cd>>(&one, 1)).front());
}

std::vector<BemSolver::Result> BemSolver::solve(double k, std::span<const std::vector<cd>> qs) {
  const std::size_t n = mesh_.elements();
  if (!(k > 0) || !std::isfinite(k)) throw InputError("bem: wavenumber must be finite and > 0");
  if (qs.empty()) return {};
  for (const auto& q : qs)
    if (q.size() != n) throw InternalError("bem: one normal derivative per element expected");
  near_field();
  std::vector<Result> out =
      n > options_.hmatrix_limit ? solve_hierarchical(k, qs) : solve_dense(k, qs);
  for (const Result& res : out)
    for (const cd& z : res.pressure)
      if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
        throw InternalError("bem: the solve produced non-finite pressures");
  return out;
}

std::vector<BemSolver::Result> BemSolver::solve_dense(double k,
                                                      std::span<const std::vector<cd>> qs) {
  const std::size_t n = mesh_.elements();
  auto t0 = std::chrono::steady_clock::now();
  std::vector<cd>& A = matrix_;
  std::vector<std::vector<cd>> bs;
  if (options_.gpu && !gpu_rows_) gpu_rows_ = std::make_unique<BemGpuRows>(options_.gpu, mesh_);
  assemble(mesh_, *near_, gpu_rows_.get(), k, qs, options_, A, bs);
  times_.assembly += seconds_since(t0);

  std::vector<Result> out(qs.size());
  const MatVec apply = [&](const cd* in, cd* y) { matvec(A, n, in, y); };
  for (std::size_t v = 0; v < qs.size(); ++v) {
    Result& res = out[v];
    const std::vector<cd>& b = bs[v];
    if (zero_right_hand_side(b, res)) continue;
    auto factorize = [&](bool single) {
      const auto tf = std::chrono::steady_clock::now();
      if (!lu_) lu_ = std::make_unique<Lu>();
      if (!lu_->factor(A, n, single)) {
        lu_.reset();
        throw InternalError("bem: the Burton-Miller matrix is singular (degenerate surface?)");
      }
      lu_->k = k;
      times_.factorization += seconds_since(tf);
      res.factorized = true;
    };
    std::vector<cd> x(n, cd(0.0));
    if (n <= options_.direct_limit) {
      // Direct: double-precision factors, computed once per frequency.
      if (!lu_ || lu_->single || lu_->k != k) factorize(false);
      x.resize(n + kPad);
      std::copy(b.begin(), b.end(), x.begin());
      lu_->solve(x.data());
      x.resize(n);
      res.residual = relative_residual(apply, b, x);
    } else {
      times_.iteration += gmres_with_nearby_factors(
          k, extent_, options_, [&] { return lu_ ? lu_->k : NAN; }, [&] { factorize(true); }, apply,
          [&](cd* y) { lu_->solve(y); }, b, kPad, res, x);
    }
    check_converged(res, options_);
    res.pressure.assign(x.begin(), x.begin() + long(n));
  }
  return out;
}

// As solve_dense's GMRES branch, with the matrix compressed and the preconditioner its
// hierarchical LU; the residual is that of the compressed matrix.
std::vector<BemSolver::Result> BemSolver::solve_hierarchical(double k,
                                                             std::span<const std::vector<cd>> qs) {
  const std::size_t n = mesh_.elements();
  auto t0 = std::chrono::steady_clock::now();
  if (!hmatrix_) hmatrix_ = std::make_unique<HMatrixSystem>(mesh_, *near_, options_);
  std::vector<std::vector<cd>> bs;
  hmatrix_->assemble(k, qs, bs);
  times_.assembly += seconds_since(t0);
  std::vector<Result> out(qs.size());
  for (std::size_t v = 0; v < qs.size(); ++v) {
    Result& res = out[v];
    if (zero_right_hand_side(bs[v], res)) continue;
    auto factorize = [&] {
      const auto tf = std::chrono::steady_clock::now();
      hmatrix_->factorize();
      times_.factorization += seconds_since(tf);
      res.factorized = true;
    };
    std::vector<cd> x(n, cd(0.0));
    times_.iteration += gmres_with_nearby_factors(
        k, extent_, options_, [&] { return hmatrix_->factorized() ? hmatrix_->factor_k() : NAN; },
        factorize, [&](const cd* in, cd* y) { hmatrix_->apply(in, y); },
        [&](cd* y) { hmatrix_->precondition(y); }, bs[v], 0, res, x);
    check_converged(res, options_);
    res.pressure = std::move(x);
  }
  return out;
}

}  // namespace chladni::precompute
