#pragma once
// A damping model drawn as a curve: the damping ratio zeta(f) = beta(omega^2) / (2 omega) at
// `steps` + 1 frequencies spaced logarithmically over [lo, hi] Hz, NaN where the model is not
// valid (a gap in the line). Shared by estimate --plot and info --plot.
#include <cmath>
#include <exception>
#include <numbers>
#include <vector>

#include "chladni/core/damping.hpp"

namespace chladni::cli {

inline void damping_curve(const DampingModel& m, double lo, double hi, int steps,
                          std::vector<double>& f, std::vector<double>& zeta) {
  for (int k = 0; k <= steps; ++k) {
    const double x = lo * std::pow(hi / lo, double(k) / steps), w = 2 * std::numbers::pi * x;
    f.push_back(x);
    try {
      zeta.push_back(m.coefficient(w) / (2 * w));
    } catch (const std::exception&) {
      zeta.push_back(NAN);
    }
  }
}

}  // namespace chladni::cli
