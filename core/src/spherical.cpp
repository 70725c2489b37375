#include "chladni/core/spherical.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace chladni {

void real_sh(int L, const Vec3& d, double* out) {
  const double r = std::sqrt(dot(d, d));
  const double x = r > 0 ? d[2] / r : 1.0;
  // (sin t cos p, sin t sin p) = (d_x, d_y) / r: powers of (c + i s) give sin^m t e^(i m p)
  // without atan2, so the normalized P_l^m below carry no sin t factor of their own.
  const double c = r > 0 ? d[0] / r : 0.0, s = r > 0 ? d[1] / r : 0.0;
  double cm = 1.0, sm = 0.0;                        // Re, Im of (c + i s)^m
  double pmm = std::sqrt(0.25 / std::numbers::pi);  // normalized P_m^m / sin^m t
  for (int m = 0; m <= L; ++m) {
    if (m > 0) {
      pmm *= std::sqrt((2.0 * m + 1.0) / (2.0 * m));
      const double nc = cm * c - sm * s;
      sm = cm * s + sm * c;
      cm = nc;
    }
    const double fc = m == 0 ? 1.0 : std::numbers::sqrt2 * cm;
    const double fs = std::numbers::sqrt2 * sm;
    // Upward in l at fixed m (Holmes & Featherstone 2002, eq. 11-12).
    double p_prev = 0.0, p = pmm;
    for (int l = m; l <= L; ++l) {
      if (l == m + 1) {
        p_prev = p;
        p = std::sqrt(2.0 * m + 3.0) * x * pmm;
      } else if (l > m + 1) {
        const double a = std::sqrt((4.0 * l * l - 1.0) / (double(l) * l - double(m) * m));
        const double b = std::sqrt(((l - 1.0) * (l - 1.0) - double(m) * m) /
                                   (4.0 * (l - 1.0) * (l - 1.0) - 1.0));
        const double next = a * (x * p - b * p_prev);
        p_prev = p;
        p = next;
      }
      out[sh_index(l, m)] = fc * p;
      if (m > 0) out[sh_index(l, -m)] = fs * p;
    }
  }
}

void sph_bessel_j(int L, double x, double* out) {
  if (x == 0.0) {
    out[0] = 1.0;
    for (int l = 1; l <= L; ++l) out[l] = 0.0;
    return;
  }
  if (x > L + 1.0) {  // upward is stable while l < x
    out[0] = std::sin(x) / x;
    if (L >= 1) out[1] = std::sin(x) / (x * x) - std::cos(x) / x;
    for (int l = 1; l < L; ++l) out[l + 1] = (2.0 * l + 1.0) / x * out[l] - out[l - 1];
    return;
  }
  // Miller: start well above max(L, x) with (0, tiny), recur down, rescale on overflow, then
  // normalize by j_0 or j_1, whichever is farther from a zero.
  const int top = std::max(L, 1);
  const int start = top + 20 + static_cast<int>(std::sqrt(40.0 * (top + x)));
  std::vector<double> f(static_cast<std::size_t>(top) + 1, 0.0);
  double fp1 = 0.0, f0 = 1e-300;
  for (int l = start; l >= 1; --l) {
    const double fm1 = (2.0 * l + 1.0) / x * f0 - fp1;
    fp1 = f0;
    f0 = fm1;  // now f_(l-1)
    if (l - 1 <= top) f[l - 1] = f0;
    if (l <= top) f[l] = fp1;
    if (std::abs(f0) > 1e250) {
      f0 *= 1e-250, fp1 *= 1e-250;
      for (int k = std::max(l - 1, 0); k <= top; ++k) f[k] *= 1e-250;
    }
  }
  const double j0 = std::sin(x) / x;
  const double j1 = std::sin(x) / (x * x) - std::cos(x) / x;
  const double scale = std::abs(j0) >= std::abs(j1) ? j0 / f[0] : j1 / f[1];
  for (int l = 0; l <= L; ++l) out[l] = f[l] * scale;
}

void sph_hankel1_scaled(int L, double x, std::complex<double>* out) {
  const std::complex<double> i(0.0, 1.0);
  out[0] = -i / x;
  if (L >= 1) out[1] = -1.0 / x - i / (x * x);
  for (int l = 1; l < L; ++l) out[l + 1] = (2.0 * l + 1.0) / x * out[l] - out[l - 1];
}

void sph_hankel1(int L, double x, std::complex<double>* out) {
  sph_hankel1_scaled(L, x, out);
  const std::complex<double> e = std::polar(1.0, x);
  for (int l = 0; l <= L; ++l) out[l] *= e;
}

void sph_hankel1_ratio(int L, double x, double x0, std::complex<double>* out) {
  const std::complex<double> i(0.0, 1.0);
  // |h_l| decreases with x, so rescaling when the x0 sequence grows large keeps both in range.
  std::complex<double> a0 = -i / x, a1 = -1.0 / x - i / (x * x);
  std::complex<double> b0 = -i / x0, b1 = -1.0 / x0 - i / (x0 * x0);
  const std::complex<double> phase = std::polar(1.0, x - x0);
  out[0] = phase * a0 / b0;
  if (L >= 1) out[1] = phase * a1 / b1;
  for (int l = 1; l < L; ++l) {
    const std::complex<double> a2 = (2.0 * l + 1.0) / x * a1 - a0;
    const std::complex<double> b2 = (2.0 * l + 1.0) / x0 * b1 - b0;
    a0 = a1, a1 = a2, b0 = b1, b1 = b2;
    if (std::abs(b1) > 1e200) {
      a0 *= 1e-200, a1 *= 1e-200, b0 *= 1e-200, b1 *= 1e-200;
    }
    out[l + 1] = phase * a1 / b1;
  }
}

std::complex<double> sph_hankel1_derivative(int l, double x) {
  std::vector<std::complex<double>> h(static_cast<std::size_t>(l) + 2);
  sph_hankel1(l + 1, x, h.data());
  if (l == 0) return -h[1];
  return h[l - 1] - (l + 1.0) / x * h[l];
}

}  // namespace chladni
