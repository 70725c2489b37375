#pragma once
// From a chord's recording to each mode's far field: least-squares separation against the
// chord's sinusoids, then the Kirchhoff-Helmholtz integral over the recording box.
#include <complex>
#include <vector>

#include "wave_grid.hpp"

namespace chladni::precompute::wave {

using cd = std::complex<double>;

/// Complex amplitudes (e^(-i w t)) per mode and recording face of p and of w, and per mode the
/// standard error of the separation relative to the mode's own amplitude.
struct Separated {
  std::size_t modes = 0, faces = 0;
  std::vector<cd> p, w;  ///< [mode][face]
  std::vector<double> error;
  double residual = 0;  ///< ||recording - fit|| / ||recording|| over the window
};
Separated separate(const Problem& problem, const std::vector<float>& samples,
                   const std::vector<double>& omega, double dt);

/// c_lm (p = sum c_lm h_l(k r) Y_lm about `centre`) of every mode m, orders <= L[m]: the
/// regular waves integrated against the box data, c_lm = i k sum_f h^2 [p d/dn(j_l Y_lm) -
/// dp/dn j_l Y_lm] with dp/dn = i k w (n outward from the box). Faces split over threads.
std::vector<std::vector<cd>> box_multipoles(const Problem& problem, const Separated& s,
                                            const std::vector<double>& k, const Vec3& centre,
                                            const std::vector<int>& L, int threads);

/// The box data's pressure at points outside the box (the Kirchhoff-Helmholtz representation).
void box_field(const Problem& problem, const Separated& s, std::size_t m, double k,
               const std::vector<Vec3>& points, cd* out, int threads);

}  // namespace chladni::precompute::wave
