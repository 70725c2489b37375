#pragma once
// Noise with a given magnitude spectrum by inverse FFT (Schreck et al. 2016 §5, after Rodet and
// Depalle 1992): each hop draws uniform random phases, inverse-transforms a 2048-sample buffer
// and overlap-adds it with 1024 samples of overlap. Consecutive buffers are uncorrelated, so
// the window is power-complementary (sine: w^2 over two hops sums to 1) and the output's
// variance is the mean of magnitude^2, matching friction_spectrum()'s normalization.
#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "chladni/core/random.hpp"

namespace chladni::runtime {

class SpectralNoise {
 public:
  static constexpr std::size_t kSize = 2048;           ///< samples per inverse FFT
  static constexpr std::size_t kHop = kSize / 2;       ///< samples out per hop
  static constexpr std::size_t kBins = kSize / 2 + 1;  ///< magnitudes per channel per hop

  /// `channels` outputs share the random phases (one source heard at several points).
  SpectralNoise(int channels, std::uint64_t seed);
  ~SpectralNoise();
  SpectralNoise(const SpectralNoise&) = delete;
  SpectralNoise& operator=(const SpectralNoise&) = delete;

  /// magnitudes: channels * kBins (channel-major); out: kHop interleaved frames, overwritten.
  void hop(std::span<const float> magnitudes, float* out);

 private:
  struct Fft;
  int channels_;
  Rng rng_;
  std::unique_ptr<Fft> fft_;
  std::vector<float> window_, tail_, phase_re_, phase_im_;
};

/// Magnitude spectrum of a recording as the friction database stores it: kFrictionBins bins
/// from 0 to fs/2 (bin k at k fs / 4096), Welch average of Hann-windowed 4096-sample segments
/// (half overlap), normalized so white noise of standard deviation s reads s in every bin.
/// Throws InputError when shorter than one segment.
inline constexpr std::size_t kFrictionBins = 2048;
std::vector<float> friction_spectrum(std::span<const float> samples);

/// The kBins magnitudes of a 2048-sample hop from a kFrictionBins spectrum (power mean of
/// bin pairs).
void spectrum_to_hop_bins(std::span<const float> spectrum, float* bins);

}  // namespace chladni::runtime
