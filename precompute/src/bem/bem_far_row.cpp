// One row of the Burton-Miller matrix by the centroid rule, over all elements at once: the loop
// the assembly spends its time in, written so the compiler vectorizes it (structure-of-arrays
// geometry, a branch-free sine/cosine) and built for AVX-512, AVX2 and the baseline.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <span>

#include "bem_kernels.hpp"

namespace chladni::precompute::bem_detail {
namespace {

// sin and cos of x >= 0 (x < 2^31 pi/2): Cody-Waite reduction by pi/2 in two parts, Taylor
// polynomials on [-pi/4, pi/4] to degree 15/16 (truncation < 5e-17), quadrant by arithmetic.
inline void sincos_reduced(double x, double& s, double& c) {
  constexpr double two_over_pi = 0.636619772367581343076;
  constexpr double pio2_1 = 1.57079632673412561417e+00, pio2_1t = 6.07710050650619224932e-11;
  constexpr double round_magic = 6755399441055744.0;  // 1.5 x 2^52: adds and rounds to integer
  const double shifted = x * two_over_pi + round_magic;
  const double q = shifted - round_magic;
  const double r = (x - q * pio2_1) - q * pio2_1t;
  const double r2 = r * r;
  const double sp =
      r * (1.0 + r2 * (-1.0 / 6 +
                       r2 * (1.0 / 120 + r2 * (-1.0 / 5040 +
                                               r2 * (1.0 / 362880 +
                                                     r2 * (-1.0 / 39916800 +
                                                           r2 * (1.0 / 6227020800 +
                                                                 r2 * (-1.0 / 1307674368000))))))));
  const double cp =
      1.0 +
      r2 * (-0.5 +
            r2 * (1.0 / 24 +
                  r2 * (-1.0 / 720 +
                        r2 * (1.0 / 40320 +
                              r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600 +
                                                           r2 * (-1.0 / 87178291200 +
                                                                 r2 * (1.0 / 20922789888000))))))));
  // The quadrant q mod 4 by arithmetic only (floor(q/2) = round(q/2 - 1/4) and floor(q/4) =
  // round(q/4 - 3/8) never round a tie), so every instruction set vectorizes the selection.
  const double half = ((q * 0.5 - 0.25) + round_magic) - round_magic;
  const double quarter = ((q * 0.25 - 0.375) + round_magic) - round_magic;
  const double odd = q - 2.0 * half;                  // 1 in quadrants 1 and 3: swap sin and cos
  const double high = half - 2.0 * quarter;           // 1 in quadrants 2 and 3: negate the sine
  const double cneg = high + odd - 2.0 * high * odd;  // 1 in quadrants 1 and 2: negate the cosine
  s = (1.0 - 2.0 * high) * (sp + odd * (cp - sp));
  c = (1.0 - 2.0 * cneg) * (cp + odd * (sp - cp));
}

// Matrix entry -K - a D (are, aim) and right-hand-side weight S + a K' (bre, bim), a = i al, of
// the pair x (normal m), y (normal ny, weight w = area / 4 pi), r = x - y.
inline void pair_kernel(double r0, double r1, double r2, double m0, double m1, double m2, double n0,
                        double n1, double n2, double w, double k, double al, double& are,
                        double& aim, double& bre, double& bim) {
  const double R2 = r0 * r0 + r1 * r1 + r2 * r2 + 1e-300;  // finite at x = y (replaced later)
  const double R = std::sqrt(R2), inv2 = 1.0 / R2, kr = k * R;
  double s, c;
  sincos_reduced(kr, s, c);
  const double sc = w / R;  // area / (4 pi R)
  const double gre = sc * c, gim = sc * s;
  const double rny = r0 * n0 + r1 * n1 + r2 * n2;
  const double rnx = r0 * m0 + r1 * m1 + r2 * m2;
  const double nn = m0 * n0 + m1 * n1 + m2 * n2;
  // G (1 - ikR) / R^2; K = that r.n_y, K' = -that r.n_x (bem_kernels.hpp, add_kernels).
  const double gpre = (gre + gim * kr) * inv2, gpim = (gim - gre * kr) * inv2;
  const double kre = gpre * rny, kim = gpim * rny, kpre = -gpre * rnx, kpim = -gpim * rnx;
  const double t = rnx * rny * inv2;
  const double hare = nn - t * (3.0 - kr * kr), haim = (3.0 * t - nn) * kr;
  const double hre = (gre * hare - gim * haim) * inv2, him = (gre * haim + gim * hare) * inv2;
  are = -kre + al * him;
  aim = -kim - al * hre;
  bre = gre - al * kpim;
  bim = gim + al * kpre;
}

// The point x (normal nxv) against elements j0 .. j0 + len of g, indexed from 0: the weights
// S + a K' into (bre, bim) and, with kEntries, the matrix entries -K - a D into (are, aim)
// (without, their arithmetic is dead and the compiler drops it). The loop the assembly spends its
// time in; inlined into each instruction-set clone below.
template <bool kEntries>
inline void point_against(const FarGeometry& g, const Vec3& x, const Vec3& nxv, std::size_t j0,
                          std::size_t len, double k, double al, double* __restrict are,
                          double* __restrict aim, double* __restrict bre, double* __restrict bim) {
  const double x0 = x[0], x1 = x[1], x2 = x[2], m0 = nxv[0], m1 = nxv[1], m2 = nxv[2];
  const double* __restrict cx = g.cx.data() + j0;
  const double* __restrict cy = g.cy.data() + j0;
  const double* __restrict cz = g.cz.data() + j0;
  const double* __restrict gnx = g.nx.data() + j0;
  const double* __restrict gny = g.ny.data() + j0;
  const double* __restrict gnz = g.nz.data() + j0;
  const double* __restrict gw = g.w.data() + j0;
  // The outputs never overlap the geometry (restrict does not always survive inlining).
#pragma GCC ivdep
  for (std::size_t l = 0; l < len; ++l) {
    double ere, eim;
    pair_kernel(x0 - cx[l], x1 - cy[l], x2 - cz[l], m0, m1, m2, gnx[l], gny[l], gnz[l], gw[l], k,
                al, ere, eim, bre[l], bim[l]);
    if constexpr (kEntries) are[l] = ere, aim[l] = eim;
  }
}

}  // namespace

__attribute__((target_clones("avx512f", "avx2", "default"))) void far_row(
    const FarGeometry& g, const Vec3& x, const Vec3& nxv, double k, double al,
    double* __restrict rre, double* __restrict rim, double* __restrict tre,
    double* __restrict tim) {
  point_against<true>(g, x, nxv, 0, g.cx.size(), k, al, rre, rim, tre, tim);
}

__attribute__((target_clones("avx512f", "avx2", "default"))) void far_rhs(
    const FarGeometry& g, const Vec3& x, const Vec3& nxv, double k, double al,
    std::span<const double* const> qre, std::span<const double* const> qim, std::size_t skip,
    std::complex<double>* out) {
  const std::size_t n = g.cx.size(), count = qre.size();
  // Weights a chunk at a time, then each sum.
  constexpr std::size_t kChunk = 256;
  double bre[kChunk], bim[kChunk];
  std::fill(out, out + count, std::complex<double>(0.0));
  for (std::size_t j0 = 0; j0 < n; j0 += kChunk) {
    const std::size_t len = std::min(kChunk, n - j0);
    point_against<false>(g, x, nxv, j0, len, k, al, nullptr, nullptr, bre, bim);
    if (skip >= j0 && skip < j0 + len) bre[skip - j0] = bim[skip - j0] = 0;  // infinite there
    for (std::size_t v = 0; v < count; ++v) {
      const double* __restrict pr = qre[v] + j0;
      const double* __restrict pi = qim[v] + j0;
      double re = 0, im = 0;
      for (std::size_t l = 0; l < len; ++l) {
        re += bre[l] * pr[l] - bim[l] * pi[l];
        im += bre[l] * pi[l] + bim[l] * pr[l];
      }
      out[v] += std::complex<double>(re, im);
    }
  }
}

__attribute__((target_clones("avx512f", "avx2", "default"))) void far_block(
    const FarGeometry& g, std::size_t row0, std::size_t m, std::size_t col0, std::size_t n,
    double k, double al, double* __restrict re, double* __restrict im) {
  const double* __restrict cx = g.cx.data();
  const double* __restrict cy = g.cy.data();
  const double* __restrict cz = g.cz.data();
  const double* __restrict gnx = g.nx.data();
  const double* __restrict gny = g.ny.data();
  const double* __restrict gnz = g.nz.data();
  const double* __restrict gw = g.w.data();
  // The inner loop runs along the longer side (a single row or column from ACA is a vector).
  if (m >= n) {
    for (std::size_t c = 0; c < n; ++c) {
      const std::size_t j = col0 + c;
      const double y0 = cx[j], y1 = cy[j], y2 = cz[j], n0 = gnx[j], n1 = gny[j], n2 = gnz[j];
      const double w = gw[j];
      double* __restrict ore = re + c * m;
      double* __restrict oim = im + c * m;
      for (std::size_t r = 0; r < m; ++r) {
        const std::size_t i = row0 + r;
        double bre, bim;
        pair_kernel(cx[i] - y0, cy[i] - y1, cz[i] - y2, gnx[i], gny[i], gnz[i], n0, n1, n2, w, k,
                    al, ore[r], oim[r], bre, bim);
      }
    }
  } else {
    for (std::size_t r = 0; r < m; ++r) {
      const std::size_t i = row0 + r;
      const double x0 = cx[i], x1 = cy[i], x2 = cz[i], m0 = gnx[i], m1 = gny[i], m2 = gnz[i];
      for (std::size_t c = 0; c < n; ++c) {
        const std::size_t j = col0 + c;
        double bre, bim;
        pair_kernel(x0 - cx[j], x1 - cy[j], x2 - cz[j], m0, m1, m2, gnx[j], gny[j], gnz[j], gw[j],
                    k, al, re[c * m + r], im[c * m + r], bre, bim);
      }
    }
  }
}

}  // namespace chladni::precompute::bem_detail
