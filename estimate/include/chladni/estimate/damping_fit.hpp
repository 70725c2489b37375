#pragma once
// The damping curve c = beta(omega^2) fitted to the features' c_j = 2 d_j (Sterling & Lin 2016,
// Eq. 1.2-1.4): weighted least squares on the logarithmic error ln(beta(omega_j^2) / c_j) (decay
// rates span decades; a curve below the data is as wrong as one above it by the same factor),
// solved exactly where the model is linear by Gauss-Newton steps. Each partial is weighted by
// the inverse of its decay's variance plus the partials' scatter about the curve (estimated from
// the fit itself, at least 2 %), and down as Huber's loss does when far off, so neither a few
// very clean partials nor one spoilt one decide the curve.
#include <string>
#include <vector>

#include "chladni/core/damping.hpp"
#include "chladni/estimate/features.hpp"

namespace chladni::estimate {

struct DampingFit {
  DampingModel model;
  double rms_relative_error = 0;  ///< weighted rms of ln(beta / c) over the partials
  std::size_t partials = 0;       ///< partials used
  double spread = 0;              ///< relative scatter of the partials about the curve, beyond
                                  ///< their measurement error (added to each one's variance)
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
