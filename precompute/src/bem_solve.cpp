// Assembly of the Burton-Miller system and its solution: LAPACK's LU (zgetrf/zgetrs through the
// BLAS) for small systems, restarted GMRES preconditioned by the LU of a nearby frequency for
// large ones.
#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <string>

#include "bem_kernels.hpp"
#include "chladni/core/error.hpp"
#include "chladni/precompute/bem.hpp"
#include "parallel.hpp"
#include "timing.hpp"

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

// The frequency-independent part of the system, computed once per mesh: for each collocation
// point the static integrals over the elements closer than far_ratio sizes (adaptive near the
// point), and the sum of the static hypersingular entries of its row (for the singularity
// subtraction below).
struct BemSolver::NearCache {
  // Static integral minus its centroid-rule value (what far_row adds), for each kernel; `close`:
  // within near_ratio sizes, where the dynamic remainder needs 3 points as well.
  struct Entry {
    uint32_t j;
    bool close;
    double single, dbl, adjoint, hyper;
  };
  std::vector<std::vector<Entry>> rows;
  std::vector<double> static_sum;
  FarGeometry far;

  NearCache(const BemMesh& m, const BemOptions& o)
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
};

namespace {

// Row i of A (into `row`, which holds the centroid-rule entries with a 0 diagonal) and b_i,
// given the far part of the right-hand side sum_(j != i) (S + a K')_j q_j: the near elements get
// their cached static corrections (and within near_ratio sizes the 3-point dynamic remainder),
// the diagonal the closed-form self term.
cd finish_row(const BemMesh& m, const BemSolver::NearCache& cache, double k, cd alpha,
              std::span<const cd> q, const BemOptions& o, std::size_t i, cd far_rhs, cd* row) {
  const Vec3 &x = m.centroid[i], &nx = m.normal[i];
  cd bi = -0.5 * alpha * q[i] - far_rhs;
  for (const auto& e : cache.rows[i]) {
    // The centroid rule gave static + dynamic: add the static correction, and close by the
    // 3-point dynamic remainder in place of the centroid one.
    cd acc[5] = {e.single, e.dbl, e.adjoint, e.hyper, 0.0};
    if (e.close) {
      const auto& t = m.triangles[e.j];
      const Rule& r = rule(3);
      for (int p = 0; p < r.n; ++p)
        add_dynamic(x, nx,
                    barycentric(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]], r.b[p]),
                    m.normal[e.j], k, r.w[p] * m.area[e.j], acc);
      add_dynamic(x, nx, m.centroid[e.j], m.normal[e.j], k, -m.area[e.j], acc);
    }
    row[e.j] += -acc[1] - alpha * acc[3];
    bi -= (acc[0] + alpha * acc[2]) * q[e.j];
  }
  // Singularity subtraction: the static hypersingular operator maps a constant density to 0 on a
  // closed surface (the Laplace double layer of a constant is piecewise constant), so its
  // diagonal is minus the sum of the row's other static entries. This removes the O(h) error
  // flat elements make on curved surfaces; only the weakly singular dynamic part of the self term
  // comes from the closed form.
  const ElementIntegrals self = element_integrals(m, uint32_t(i), x, nx, k, o);
  row[i] = 0.5 - alpha * (self.hyper - self.hyper_static - cache.static_sum[i]);
  return bi - self.single * q[i];
}

// Row-major A (A[i * n + j]: collocation point i, element j) and b = B q: every row first by
// the centroid rule (far_row, or the device's rows), then finish_row.
void assemble(const BemMesh& m, const BemSolver::NearCache& cache, BemGpuRows* gpu, double k,
              std::span<const cd> q, const BemOptions& o, std::vector<cd>& A, std::vector<cd>& b) {
  const std::size_t n = m.elements();
  // Every entry is written below: reuse the buffer rather than zero-filling (and page-faulting)
  // hundreds of megabytes per frequency.
  if (A.size() != n * n + kPad) A.assign(n * n + kPad, cd(0.0));
  b.assign(n, cd(0.0));
  // Burton-Miller coupling i/k, but no larger than i h (h: the mean element size). Any coupling
  // with a positive imaginary part makes the solution unique; the hypersingular equation's
  // discretization on flat elements is only first order in h, and weighting it by h keeps the
  // combination second order (on a sphere at ka = 0.1: 21 % error with i/k, 0.3 % with i h).
  const cd alpha(0.0, std::min(1.0 / k, o.coupling_scale * m.mean_size()));
  if (gpu) {  // centroid-rule rows on the device, block by block; the rest on the CPU
    std::vector<std::complex<float>> entries, rhs;
    for (std::size_t r0 = 0; r0 < n; r0 += gpu->block_rows()) {
      const std::size_t count = std::min(gpu->block_rows(), n - r0);
      gpu->rows(k, alpha.imag(), q, r0, count, entries, rhs);
      parallel_for(count, o.threads, [&](std::size_t a, std::size_t e) {
        for (std::size_t r = a; r < e; ++r) {
          cd* row = A.data() + (r0 + r) * n;
          for (std::size_t j = 0; j < n; ++j) row[j] = cd(entries[r * n + j]);
          b[r0 + r] = finish_row(m, cache, k, alpha, q, o, r0 + r, cd(rhs[r]), row);
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
      cd far_rhs = 0;
      for (std::size_t j = 0; j < n; ++j) {
        row[j] = cd(rre[j], rim[j]);
        far_rhs += cd(tre[j], tim[j]) * q[j];
      }
      b[i] = finish_row(m, cache, k, alpha, q, o, i, far_rhs, row);
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

double norm2(const std::vector<cd>& v) {
  double s = 0;
  for (const cd& z : v) s += std::norm(z);
  return std::sqrt(s);
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

// Restarted GMRES(m) with right preconditioning: A M^-1 z = b, x = M^-1 z, from the x given.
// Returns the iterations taken.
int gmres(const std::vector<cd>& A, const std::vector<cd>& b, const BemSolver::Lu& M,
          const BemOptions& o, std::vector<cd>& x) {
  const std::size_t n = b.size();
  const double nb = norm2(b);
  const int m = o.gmres_restart;
  std::vector<std::vector<cd>> V(std::size_t(m) + 1, std::vector<cd>(n + kPad));
  Eigen::MatrixXcd H = Eigen::MatrixXcd::Zero(m + 1, m);
  std::vector<cd> r(n), w(n + kPad), g(std::size_t(m) + 1);
  std::vector<cd> cs(static_cast<std::size_t>(m)), sn(static_cast<std::size_t>(m));
  int total = 0;
  while (total < o.gmres_max_iterations) {
    matvec(A, n, x.data(), r.data());
    for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - r[i];
    const double beta = norm2(r);
    if (beta / nb <= o.gmres_tolerance) break;
    for (std::size_t i = 0; i < n; ++i) V[0][i] = r[i] / beta;
    std::fill(g.begin(), g.end(), cd(0.0));
    g[0] = beta;
    int j = 0;
    for (; j < m && total < o.gmres_max_iterations; ++j, ++total) {
      std::copy(V[j].begin(), V[j].begin() + long(n), w.begin());
      M.solve(w.data());
      matvec(A, n, w.data(), V[j + 1].data());
      auto& v = V[j + 1];
      for (int i = 0; i <= j; ++i) {  // modified Gram-Schmidt
        cd h = 0;
        for (std::size_t e = 0; e < n; ++e) h += std::conj(V[i][e]) * v[e];
        H(i, j) = h;
        for (std::size_t e = 0; e < n; ++e) v[e] -= h * V[i][e];
      }
      double hn = 0;
      for (std::size_t e = 0; e < n; ++e) hn += std::norm(v[e]);
      hn = std::sqrt(hn);
      H(j + 1, j) = hn;
      if (hn > 0)
        for (std::size_t e = 0; e < n; ++e) v[e] /= hn;
      for (int i = 0; i < j; ++i) {  // previous Givens rotations
        const cd t = cs[i] * H(i, j) + sn[i] * H(i + 1, j);
        H(i + 1, j) = -std::conj(sn[i]) * H(i, j) + std::conj(cs[i]) * H(i + 1, j);
        H(i, j) = t;
      }
      const double den = std::sqrt(std::norm(H(j, j)) + std::norm(H(j + 1, j)));
      cs[j] = den > 0 ? H(j, j) / den : 1.0;
      sn[j] = den > 0 ? H(j + 1, j) / den : 0.0;
      H(j, j) = den;
      H(j + 1, j) = 0;
      g[j + 1] = -std::conj(sn[j]) * g[j];
      g[j] = std::conj(cs[j]) * g[j];
      if (std::abs(g[j + 1]) / nb <= o.gmres_tolerance || hn == 0) {
        ++j, ++total;
        break;
      }
    }
    // x += M^-1 V y with H y = g (upper triangular j x j).
    Eigen::VectorXcd y(j);
    for (int i = j - 1; i >= 0; --i) {
      cd s = g[i];
      for (int c = i + 1; c < j; ++c) s -= H(i, c) * y(c);
      y(i) = s / H(i, i);
    }
    std::fill(w.begin(), w.end(), cd(0.0));
    for (int i = 0; i < j; ++i)
      for (std::size_t e = 0; e < n; ++e) w[e] += y(i) * V[i][e];
    M.solve(w.data());
    for (std::size_t e = 0; e < n; ++e) x[e] += w[e];
  }
  return total;
}

double residual(const std::vector<cd>& A, const std::vector<cd>& b, const std::vector<cd>& x) {
  const std::size_t n = b.size();
  std::vector<cd> ax(n);
  matvec(A, n, x.data(), ax.data());
  for (std::size_t i = 0; i < n; ++i) ax[i] -= b[i];
  return norm2(ax) / norm2(b);
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

BemSolver::~BemSolver() = default;

BemSolver::Result BemSolver::solve(double k, std::span<const cd> q) {
  const std::size_t n = mesh_.elements();
  if (!(k > 0) || !std::isfinite(k)) throw InputError("bem: wavenumber must be finite and > 0");
  if (q.size() != n) throw InternalError("bem: one normal derivative per element expected");
  auto t0 = std::chrono::steady_clock::now();
  if (!near_) near_ = std::make_unique<NearCache>(mesh_, options_);
  std::vector<cd>&A = matrix_, b;
  if (options_.gpu && !gpu_rows_) gpu_rows_ = std::make_unique<BemGpuRows>(options_.gpu, mesh_);
  assemble(mesh_, *near_, gpu_rows_.get(), k, q, options_, A, b);
  times_.assembly += seconds_since(t0);

  Result res;
  const double nb = norm2(b);
  if (!(nb > 0)) {
    res.pressure.assign(n, cd(0.0));
    return res;
  }
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
  t0 = std::chrono::steady_clock::now();
  std::vector<cd> x(n, cd(0.0));
  if (n <= options_.direct_limit) {
    factorize(false);
    x.resize(n + kPad);
    std::copy(b.begin(), b.end(), x.begin());
    lu_->solve(x.data());
    x.resize(n);
    res.residual = residual(A, b, x);
  } else {
    // Factors of a frequency within 1 / extent precondition GMRES in under ~40 iterations (the
    // phase of e^(ikR) across the object moves by less than 1 rad; on the bowl at 3 kHz, 21
    // iterations at 0.7 rad, 39 at 1.4, no convergence in 60 at 2.1); farther ones are not worth
    // trying: factorize here.
    if (!lu_ || std::abs(k - lu_->k) * extent_ > options_.refactor_phase) factorize(true);
    t0 = std::chrono::steady_clock::now();
    res.iterations = gmres(A, b, *lu_, options_, x);
    res.residual = residual(A, b, x);
    if (!(res.residual <= 10 * options_.gmres_tolerance) && lu_->k != k) {
      times_.iteration += seconds_since(t0);
      factorize(true);
      t0 = std::chrono::steady_clock::now();
      std::fill(x.begin(), x.end(), cd(0.0));
      res.iterations += gmres(A, b, *lu_, options_, x);
      res.residual = residual(A, b, x);
    }
    times_.iteration += seconds_since(t0);
  }
  if (!(res.residual <= 10 * options_.gmres_tolerance))
    throw InternalError("bem: the solve did not converge (relative residual " +
                        std::to_string(res.residual) + " after " + std::to_string(res.iterations) +
                        " GMRES iterations)");
  res.pressure.assign(x.begin(), x.begin() + long(n));
  for (const cd& z : res.pressure) {
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
      throw InternalError("bem: the solve produced non-finite pressures");
  }
  return res;
}

}  // namespace chladni::precompute
