#pragma once
// Modal features of a recorded strike (Ren et al. 2013, Sterling & Lin 2016 Sec. 1.3.1.1): each
// feature is one exponentially decaying partial A e^{-d t} cos(2 pi f t + phi), with t from the
// recording's peak. Peaks of the residual's spectrum are fitted one at a time in the
// time-frequency plane and subtracted until a set share of the energy is explained.
#include <cstddef>
#include <span>
#include <vector>

namespace chladni::estimate {

struct Feature {
  double frequency = 0;        ///< Hz
  double decay = 0;            ///< d (1/s): amplitude e^{-d t}; damping c = 2 d
  double amplitude = 0;        ///< A at the peak, full scale 1
  double phase = 0;            ///< phi (rad) at the peak
  double frequency_sigma = 0;  ///< standard error of the frequency (Hz)
  double decay_sigma = 0;      ///< standard error of d (1/s)
  double energy_share = 0;     ///< the partial's energy over the analysed signal's
  std::size_t window = 0;      ///< frame length of the fit (samples)
  std::size_t frames = 0;      ///< frames the decay was fitted over
  /// Damping ratio d / omega.
  double damping_ratio() const;
};

struct FeatureOptions {
  double explained = 0.9;         ///< stop once this share of the energy is explained
  std::size_t max_features = 64;  ///< at most this many partials
  /// ... but at least this many while peaks stand above the noise, so that a strike whose
  /// fundamental carries most of the energy still gives a damping curve.
  std::size_t min_features = 24;
  double min_frequency = 20;  ///< Hz
  double max_frequency = 0;   ///< Hz; 0: 0.45 of the sample rate
  double min_snr_db = 12;     ///< a peak must stand this far above the spectrum's floor
  int threads = 0;            ///< candidates of a round fitted in parallel; 0: all cores
};

struct FeatureSet {
  std::vector<Feature> features;  ///< by frequency
  double explained = 0;           ///< share of the energy the features explain
  std::size_t origin = 0;         ///< sample index of the peak (t = 0 of the features)
  double sample_rate = 0;
  double duration = 0;           ///< seconds analysed from the peak
  std::vector<double> residual;  ///< what the features leave, from the peak on
};

/// Features of `x` (mono, sample rate `fs`). Analysis starts at the largest sample, or after the
/// last clipped one when three or more sit at the largest magnitude. Throws InputError for a bad
/// option, never for a quiet signal: then it returns fewer features.
FeatureSet extract_features(std::span<const double> x, double fs, const FeatureOptions& options);

/// Sum of the features' partials over `frames` samples from t = 0.
std::vector<double> synthesize(const std::vector<Feature>& features, double fs, std::size_t frames);

}  // namespace chladni::estimate
