#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "chladni/plot/figure.hpp"

namespace chladni::plot {

Spectrogram spectrogram(const std::vector<double>& x, double fs, std::size_t n, std::size_t hop,
                        std::size_t max_frames) {
  Spectrogram s;
  s.bins = n / 2 + 1;
  s.bin_hz = fs / double(n);
  const std::size_t hops = x.size() > n ? (x.size() - n) / hop + 1 : 1;
  // Long sounds: every hop is analysed, then `pool` of them are merged (the loudest per bin), so
  // a short impact between kept frames still shows and memory stays bounded.
  const std::size_t pool =
      (hops + std::max<std::size_t>(max_frames, 1) - 1) / std::max<std::size_t>(max_frames, 1);
  s.frames = (hops + pool - 1) / pool;
  s.hop_s = double(hop * pool) / fs;
  s.db.assign(s.frames * s.bins, -300.0f);
  std::vector<double> in(n), w(n);
  std::vector<std::complex<double>> out(s.bins);
  double wsum2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    w[i] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * (double(i) + 0.5) / double(n));
    wsum2 += w[i] * w[i];
  }
  fftw_plan plan = fftw_plan_dft_r2c_1d(int(n), in.data(),
                                        reinterpret_cast<fftw_complex*>(out.data()), FFTW_ESTIMATE);
  for (std::size_t h = 0; h < hops; ++h) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = h * hop + i;
      in[i] = k < x.size() ? x[k] * w[i] : 0.0;
    }
    fftw_execute(plan);
    // Power of a sinusoid of amplitude A: (A^2 / 2) at its bin's neighbourhood's sum.
    float* row = &s.db[(h / pool) * s.bins];
    for (std::size_t j = 0; j < s.bins; ++j)
      row[j] = std::max(
          row[j], float(10 * std::log10(2 * std::norm(out[j]) / (double(n) * wsum2) + 1e-30)));
  }
  fftw_destroy_plan(plan);
  return s;
}

}  // namespace chladni::plot
