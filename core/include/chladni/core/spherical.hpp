#pragma once
// Spherical special functions for multipole expansions (DESIGN.md conventions): real orthonormal
// spherical harmonics, spherical Bessel j_l and Hankel h_l^(1) functions. Double precision; the
// GPU kernels carry float versions of the same recurrences.
#include <complex>
#include <cstddef>

#include "chladni/core/vec3.hpp"

namespace chladni {

/// Index of (l, m), -l <= m <= l, in a flat array of orders 0..L: l^2 + l + m.
constexpr std::size_t sh_index(int l, int m) {
  return static_cast<std::size_t>(l * l + l + m);
}
/// Number of (l, m) pairs with l <= L.
constexpr std::size_t sh_count(int L) {
  return static_cast<std::size_t>((L + 1) * (L + 1));
}

/// Real orthonormal spherical harmonics Y_lm(d), l <= L, of a direction d (need not be unit;
/// the zero vector counts as +z). Y_l0 = N_l0 P_l(cos t), Y_l,m>0 = sqrt2 N_lm P_l^m cos(m p),
/// Y_l,-m = sqrt2 N_lm P_l^m sin(m p), without the Condon-Shortley phase. Sum_m Y_lm(a) Y_lm(b) =
/// (2l+1)/(4 pi) P_l(a.b), so they replace complex harmonics in the addition theorem.
void real_sh(int L, const Vec3& d, double* out);

/// j_l(x), l = 0..L, x >= 0 (Miller's downward recurrence, normalized by sum (2l+1) j_l^2 = 1).
void sph_bessel_j(int L, double x, double* out);

/// h_l^(1)(x) = j_l + i y_l, l = 0..L, x > 0 (upward recurrence, stable for the dominant y_l).
void sph_hankel1(int L, double x, std::complex<double>* out);

/// h_l^(1)(x) e^(-ix): a polynomial in 1/x that satisfies the same recurrence; ratios of it at
/// two radii need no trigonometry.
void sph_hankel1_scaled(int L, double x, std::complex<double>* out);

/// h_l^(1)(x) / h_l^(1)(x0), l = 0..L, for x >= x0 > 0: both recurrences share one rescaling, so
/// orders whose h_l(x0) alone would overflow still give their (small) ratio.
void sph_hankel1_ratio(int L, double x, double x0, std::complex<double>* out);

/// d/dx h_l^(1)(x) = h_(l-1)(x) - (l+1)/x h_l(x) (h_0' = -h_1).
std::complex<double> sph_hankel1_derivative(int l, double x);

}  // namespace chladni
