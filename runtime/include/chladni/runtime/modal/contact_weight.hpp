#pragma once
// Impact excitation (DESIGN.md): an impulse J along n at surface point x gives mode i the response
//   q_i(t) = (v_i(x) . n) J / omega_d * exp(-d t) sin(omega_d t).
// A finite contact of duration tau is modelled as a half-sine force F(t) = F0 sin(pi t / tau)
// with integral J; its spectrum at the mode's complex frequency weights the mode.
#include <complex>

namespace chladni::runtime {

/// W = integral_0^tau F(s) exp(-lambda s) ds with lambda = -d + i omega_d, so that for t >= tau
/// the mode responds as Im(W exp(lambda t)) / omega_d. W = J for tau = 0 (an ideal impulse).
std::complex<double> contact_weight(double impulse, double contact_time, double omega_d,
                                    double decay);

}  // namespace chladni::runtime
