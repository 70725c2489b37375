#pragma once
// One partial fitted in the time-frequency plane: the short-time Fourier transform of a damped
// sinusoid, taken at its own frequency, is X(t) = (A/2) e^{i phi} W e^{(i Delta - d) t} (W the
// window's transform at the offset Delta and decay d), so ln X is linear in t: its real slope
// is -d and its imaginary slope the frequency offset.
#include <vector>

#include "chladni/estimate/features.hpp"

namespace chladni::estimate {

/// The frame lengths tried at sample rate fs (about 6 ms to 0.75 s) and their Hann windows,
/// made once per analysis and then only read (fits run on several threads).
class HannWindows {
 public:
  explicit HannWindows(double fs);
  const std::vector<std::vector<double>>& all() const { return windows_; }

 private:
  std::vector<std::vector<double>> windows_;  ///< by increasing length
};

/// Fits the partial near `frequency` (Hz) in r (t = 0 at r[0]); noise_sigma is the local noise
/// deviation per sample. Tries several frame lengths and keeps the one whose decay has the
/// smallest standard error. False when no frame length gives four frames above the noise.
bool fit_partial(const std::vector<double>& r, double fs, double frequency, double noise_sigma,
                 const HannWindows& windows, Feature& out);

/// r += gain * A e^{-d t} cos(2 pi f t + phi) over all of r.
void add_partial(std::vector<double>& r, double fs, const Feature& f, double gain);

inline void subtract_partial(std::vector<double>& r, double fs, const Feature& f) {
  add_partial(r, fs, f, -1.0);
}

}  // namespace chladni::estimate
