// One row of the Burton-Miller matrix by the centroid rule, over all elements at once: the loop
// the assembly spends its time in, written so the compiler vectorizes it (structure-of-arrays
// geometry, a branch-free sine/cosine) and built for AVX-512, AVX2 and the baseline.
#include <cmath>
#include <cstdint>
#include <numbers>

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

}  // namespace

__attribute__((target_clones("avx512f", "avx2", "default"))) void far_row(
    const FarGeometry& g, const Vec3& x, const Vec3& nxv, double k, double al,
    double* __restrict rre, double* __restrict rim, double* __restrict tre,
    double* __restrict tim) {
  const std::size_t n = g.cx.size();
  const double x0 = x[0], x1 = x[1], x2 = x[2], m0 = nxv[0], m1 = nxv[1], m2 = nxv[2];
  const double* __restrict cx = g.cx.data();
  const double* __restrict cy = g.cy.data();
  const double* __restrict cz = g.cz.data();
  const double* __restrict gnx = g.nx.data();
  const double* __restrict gny = g.ny.data();
  const double* __restrict gnz = g.nz.data();
  const double* __restrict gw = g.w.data();
  for (std::size_t j = 0; j < n; ++j) {
    const double r0 = x0 - cx[j], r1 = x1 - cy[j], r2 = x2 - cz[j];
    const double d2 = r0 * r0 + r1 * r1 + r2 * r2;
    const double R2 = d2 + 1e-300;  // finite at j = i, whose entry the caller replaces
    const double R = std::sqrt(R2), inv2 = 1.0 / R2, kr = k * R;
    double s, c;
    sincos_reduced(kr, s, c);
    const double sc = gw[j] / R;  // area / (4 pi R)
    const double gre = sc * c, gim = sc * s;
    const double rny = r0 * gnx[j] + r1 * gny[j] + r2 * gnz[j];
    const double rnx = r0 * m0 + r1 * m1 + r2 * m2;
    const double nn = m0 * gnx[j] + m1 * gny[j] + m2 * gnz[j];
    // G (1 - ikR) / R^2; K = that r.n_y, K' = -that r.n_x (bem_kernels.hpp, add_kernels).
    const double gpre = (gre + gim * kr) * inv2, gpim = (gim - gre * kr) * inv2;
    const double kre = gpre * rny, kim = gpim * rny, kpre = -gpre * rnx, kpim = -gpim * rnx;
    const double t = rnx * rny * inv2;
    const double are = nn - t * (3.0 - kr * kr), aim = (3.0 * t - nn) * kr;
    const double hre = (gre * are - gim * aim) * inv2, him = (gre * aim + gim * are) * inv2;
    // Row entry -K - a D and right-hand-side weight S + a K' with a = i al.
    rre[j] = -kre + al * him;
    rim[j] = -kim - al * hre;
    tre[j] = gre - al * kpim;
    tim[j] = gim + al * kpre;
  }
}

}  // namespace chladni::precompute::bem_detail
