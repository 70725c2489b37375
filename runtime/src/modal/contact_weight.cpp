#include "chladni/runtime/modal/contact_weight.hpp"

#include <cmath>
#include <numbers>

namespace chladni::runtime {

std::complex<double> contact_weight(double J, double tau, double omega_d, double decay) {
  if (tau <= 0.0) return {J, 0.0};
  using C = std::complex<double>;
  const C lambda(-decay, omega_d);
  const double b = std::numbers::pi / tau;
  // Closed form for F = (J b / 2) sin(b s) on [0, tau] (sin(b tau) = 0, cos(b tau) = -1):
  //   W = J b^2 (1 + exp(-lambda tau)) / (2 (lambda^2 + b^2)).
  const C den = lambda * lambda + b * b;
  if (std::abs(den) > 1e-6 * b * b)
    return J * b * b * (1.0 + std::exp(-lambda * tau)) / (2.0 * den);
  // Near resonance (omega_d ~ pi / tau, tiny decay) the closed form is 0/0: integrate instead
  // (composite Simpson over a smooth, half-period integrand).
  constexpr int n = 256;
  C sum = 0.0;
  for (int k = 0; k <= n; ++k) {
    const double s = tau * k / n;
    const double w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
    sum += w * (0.5 * J * b * std::sin(b * s)) * std::exp(-lambda * s);
  }
  return sum * (tau / (3.0 * n));
}

}  // namespace chladni::runtime
