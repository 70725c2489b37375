#include "chladni/runtime/paper/spectral_noise.hpp"

#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

#include "../real_fft.hpp"
#include "chladni/core/error.hpp"

namespace chladni::runtime {

struct SpectralNoise::Fft {
  RealFft plan{SpectralNoise::kSize, true};
};

SpectralNoise::SpectralNoise(int channels, std::uint64_t seed)
    : channels_(channels), rng_(seed), fft_(std::make_unique<Fft>()) {
  if (channels < 1) throw InternalError("SpectralNoise: channels must be >= 1");
  window_.resize(kSize);
  for (std::size_t i = 0; i < kSize; ++i)
    window_[i] = static_cast<float>(std::sin(std::numbers::pi * (i + 0.5) / kSize));
  tail_.assign(kHop * channels, 0.0f);
  phase_re_.resize(kBins);
  phase_im_.resize(kBins);
}

SpectralNoise::~SpectralNoise() = default;

void SpectralNoise::hop(std::span<const float> magnitudes, float* out) {
  if (magnitudes.size() != kBins * channels_) throw InternalError("SpectralNoise: bin count");
  for (std::size_t k = 0; k < kBins; ++k) {
    const double phi = 2 * std::numbers::pi * rng_.uniform();
    phase_re_[k] = static_cast<float>(std::cos(phi));
    phase_im_[k] = static_cast<float>(std::sin(phi));
  }
  // |Y_k| = M_k sqrt(N); y = c2r(Y) / N has variance mean(M^2) (unnormalized inverse).
  const float scale = 1.0f / std::sqrt(float(kSize));
  RealFft& p = fft_->plan;
  for (int c = 0; c < channels_; ++c) {
    const float* mag = magnitudes.data() + c * kBins;
    for (std::size_t k = 0; k < kBins; ++k) {
      p.spec[k].r = mag[k] * phase_re_[k];
      p.spec[k].i = mag[k] * phase_im_[k];
    }
    p.spec[0].i = p.spec[kBins - 1].i = 0;  // DC and Nyquist are real
    p.execute();
    float* tail = tail_.data() + c * kHop;
    for (std::size_t i = 0; i < kHop; ++i) {
      out[i * channels_ + c] = tail[i] + p.real[i] * window_[i] * scale;
      tail[i] = p.real[kHop + i] * window_[kHop + i] * scale;
    }
  }
}

std::vector<float> friction_spectrum(std::span<const float> samples) {
  constexpr std::size_t n = 2 * kFrictionBins;
  if (samples.size() < n) {
    throw InputError("a friction recording needs at least " + std::to_string(n) +
                     " samples to measure its spectrum, this one has " +
                     std::to_string(samples.size()));
  }
  RealFft p(n, false);
  std::vector<double> w(n), power(kFrictionBins, 0.0);
  double w2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    w[i] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * i / n);
    w2 += w[i] * w[i];
  }
  std::size_t segments = 0;
  for (std::size_t start = 0; start + n <= samples.size(); start += n / 2, ++segments) {
    for (std::size_t i = 0; i < n; ++i) p.real[i] = static_cast<float>(samples[start + i] * w[i]);
    p.execute();
    for (std::size_t k = 0; k < kFrictionBins; ++k)
      power[k] += double(p.spec[k].r) * p.spec[k].r + double(p.spec[k].i) * p.spec[k].i;
  }
  std::vector<float> out(kFrictionBins);
  for (std::size_t k = 0; k < kFrictionBins; ++k)
    out[k] = static_cast<float>(std::sqrt(power[k] / (segments * w2)));
  return out;
}

void spectrum_to_hop_bins(std::span<const float> s, float* bins) {
  for (std::size_t k = 0; k + 1 < SpectralNoise::kBins; ++k) {
    const double a = s[2 * k], b = s[2 * k + 1];
    bins[k] = static_cast<float>(std::sqrt(0.5 * (a * a + b * b)));
  }
  bins[SpectralNoise::kBins - 1] = 0;
}

}  // namespace chladni::runtime
