#pragma once
// The similarity metric of Ren et al. 2013 as used by Sterling & Lin 2016 (Eq. 1.5-1.9): a
// psychoacoustic spectrogram difference divided by the Match Ratio Product of the two sets of
// partials. Lower is better.
#include <cstddef>
#include <span>
#include <vector>

namespace chladni::estimate {

/// One exponentially decaying partial: A e^{-d t} cos(2 pi f t + ...), t from the strike.
struct Partial {
  double frequency = 0;  ///< Hz
  double decay = 0;      ///< 1/s
  double amplitude = 0;  ///< at t = 0
};

/// Critical-band rate z (Bark) of f (Hz): Zwicker & Terhardt 1980.
double bark(double f);

/// T(I) of Eq. 1.5: frames of a Hann STFT (about 46 ms, half overlapping) from the strike on,
/// power summed into half-Bark bands and turned into specific loudness (sone/Bark) by Zwicker's
/// formula N' = 0.08 (E_TQ/E0)^0.23 [(0.5 + 0.5 E/E_TQ)^0.23 - 1] with Terhardt's threshold in
/// quiet (Zwicker & Fastl, Psychoacoustics, Eq. 8.7). Levels are referred to the recording: its
/// loudest band and frame is taken as 90 dB SPL, and a model is measured on the same scale.
class PsychoSpectrogram {
 public:
  /// The spectrogram of x (x[0] = the strike) at sample rate fs; sets the level reference.
  PsychoSpectrogram(std::span<const double> x, double fs, double max_frequency);
  /// The same frames and bands for a sum of partials, analytically: each partial's power
  /// (A^2/2) e^{-2 d t} over the frame's window, spread over the bins by the window's kernel,
  /// plus the noise floor.
  std::vector<float> of_partials(std::span<const Partial> partials) const;
  /// Sets the noise floor added to every model frame: per band, the median over frames of the
  /// power of `residual` (what the features leave: the recording's noise, stationary, where a
  /// model of partials alone would have silence).
  void set_noise(std::span<const double> residual);
  const std::vector<float>& loudness() const { return loudness_; }
  std::size_t frames() const { return frames_; }
  std::size_t bands() const { return edges_.size() - 1; }
  /// Pi_psycho (Eq. 1.5): the sum of squared differences from this spectrogram.
  double difference(std::span<const float> other) const;

 private:
  void to_loudness(const std::vector<double>& power, std::vector<float>& out) const;
  std::vector<double> band_power(std::span<const double> x) const;
  double fs_ = 0, reference_ = 1;
  std::size_t window_ = 0, hop_ = 0, frames_ = 0;
  std::vector<double> edges_;      ///< band edges (Hz)
  std::vector<double> threshold_;  ///< E_TQ / E0 per band
  std::vector<double> noise_;      ///< noise power per band
  std::vector<float> loudness_;    ///< frames x bands
};

/// The set-to-set match ratio R(a, b) (Eq. 1.6-1.7): each partial of `a` is compared with every
/// partial of `b` by k = exp(-((dz / 0.5 Bark)^2 + (d ln tau / ln 2)^2) / 2), tau = 1/d its
/// duration; the point-to-set ratio weights b's partials by their prominence (energy) times k,
/// so it reads as the closeness of a's partial to its prominent near matches; the set-to-set
/// ratio weights a's partials by their prominence. 1 is a perfect match.
double match_ratio(std::span<const Partial> a, std::span<const Partial> b, double duration);

/// Pi_MRP = -R(a, b) R(b, a) (Eq. 1.8).
double match_ratio_product(std::span<const Partial> a, std::span<const Partial> b, double duration);

/// Pi_hybrid = Pi_psycho / |Pi_MRP| (Eq. 1.9; Pi_MRP is negative, its magnitude divides).
double hybrid_metric(double psycho, double mrp);

}  // namespace chladni::estimate
