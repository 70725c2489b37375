#pragma once
// Generalized proportional damping (Sterling & Lin 2016, Eq. 1.1-1.4): each mode's damping
// coefficient is c_i = beta(omega_i^2), with beta one of the models below (DESIGN.md).
#include <string>
#include <string_view>
#include <vector>

namespace chladni {

struct DampingModel {
  enum class Kind { Rayleigh, Caughey, PowerLaw, Hybrid };
  Kind kind = Kind::Rayleigh;
  // Rayleigh: {a1, a2}; Caughey: {a1, ..., aN}; PowerLaw: {a1, a2}; Hybrid: {r1, r2, p1, p2}.
  std::vector<double> alpha = {0.0, 0.0};

  /// c = beta(omega^2) in 1/s. Throws InputError when the result is negative or not finite.
  double coefficient(double omega) const;

  /// Checks that the parameters are finite and of the right count; throws InputError otherwise.
  void validate() const;

  /// "rayleigh:A1,A2", "caughey:A1,A2,...", "power:A1,A2", "hybrid:R1,R2,P1,P2".
  static DampingModel parse(std::string_view text);
  std::string to_string() const;
};

/// The damping ratio zeta(f) = beta(omega^2) / (2 omega) at `steps` + 1 frequencies spaced
/// logarithmically over [lo, hi] Hz, appended to `f` and `zeta`; NaN where the model gives no
/// valid coefficient (a gap when drawn).
void damping_ratio_curve(const DampingModel& model, double lo, double hi, int steps,
                         std::vector<double>& f, std::vector<double>& zeta);

}  // namespace chladni
