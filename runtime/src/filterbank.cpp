#include "chladni/runtime/filterbank.hpp"

#include <cmath>

namespace chladni::runtime {

std::complex<float> pole(double omega_d, double decay, double sample_rate) {
  // p = exp((-d + i omega_d) / fs), formed in double before rounding to float.
  const double r = std::exp(-decay / sample_rate);
  const double a = omega_d / sample_rate;
  return {static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a))};
}

}  // namespace chladni::runtime
