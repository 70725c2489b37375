#pragma once
// The damping curve c = beta(omega^2) fitted to the features' c_j = 2 d_j (Sterling & Lin 2016,
// Eq. 1.2-1.4): weighted least squares on the relative error beta(omega_j^2) / c_j - 1, each
// partial weighted by the inverse variance of its decay plus a 2 % floor, so a few very clean
// partials cannot pull the curve alone.
#include <string>
#include <vector>

#include "chladni/core/damping.hpp"
#include "chladni/estimate/features.hpp"

namespace chladni::estimate {

struct DampingFit {
  DampingModel model;
  double rms_relative_error = 0;  ///< weighted rms of beta / c - 1 over the partials
  std::size_t partials = 0;       ///< partials used
  std::vector<std::string> warnings;
};

/// Parses "rayleigh", "caughey:K" (K terms, 1 to 6), "power" or "hybrid" into a model of that
/// kind with K zero parameters. Throws InputError naming the text.
DampingModel damping_kind(const std::string& text);

/// Fits a model of `shape`'s kind (and parameter count) to the features. Partials with no decay
/// (d <= 0) are left out. Throws InputError when fewer partials remain than the model has
/// parameters.
DampingFit fit_damping(const std::vector<Feature>& features, const DampingModel& shape);

}  // namespace chladni::estimate
