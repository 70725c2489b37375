#include "chladni/estimate/metric.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace chladni::estimate {
namespace {

constexpr double kPi = std::numbers::pi;

// Terhardt's threshold in quiet (dB SPL), f in Hz.
double threshold_db(double f) {
  const double k = std::max(f, 20.0) / 1000;
  return 3.64 * std::pow(k, -0.8) - 6.5 * std::exp(-0.6 * (k - 3.3) * (k - 3.3)) +
         1e-3 * std::pow(k, 4);
}

// |W(delta)|^2 of a Hann window, delta in bins, normalized so the bins sum to 1: with W(0) =
// 1/2 the sum of |W|^2 over integer offsets is 1/4 + 2/16 = 3/8 (Parseval: M sum w^2 = 3M^2/8).
double hann_kernel_exact(double delta) {
  auto D = [](double x) { return std::abs(x) < 1e-9 ? 1.0 : std::sin(kPi * x) / (kPi * x); };
  const double W = 0.5 * D(delta) + 0.25 * D(delta - 1) + 0.25 * D(delta + 1);
  return W * W / 0.375;
}

// The same from a table at 1/256 bin, linearly interpolated (the metric evaluates it for every
// mode at every step of the search).
double hann_kernel(double delta) {
  constexpr int kPerBin = 256, kHalf = 9 * kPerBin;
  static const std::vector<double> table = [] {
    std::vector<double> t(2 * kHalf + 2);
    for (int i = 0; i < int(t.size()); ++i) t[i] = hann_kernel_exact(double(i - kHalf) / kPerBin);
    return t;
  }();
  const double u = delta * kPerBin + kHalf;
  if (u < 0 || u >= 2 * kHalf) return 0.0;
  const int i = int(u);
  return table[i] + (u - i) * (table[i + 1] - table[i]);
}

double prominence(const Partial& p, double duration) {
  const double d = std::max(p.decay, 1e-6);
  return p.amplitude * p.amplitude / (4 * d) * (1 - std::exp(-2 * d * duration));
}

}  // namespace

double bark(double f) {
  return 13 * std::atan(0.00076 * f) + 3.5 * std::atan((f / 7500) * (f / 7500));
}

PsychoSpectrogram::PsychoSpectrogram(std::span<const double> x, double fs, double max_frequency)
    : fs_(fs) {
  window_ = 256;
  while (double(window_) < 0.046 * fs) window_ <<= 1;
  hop_ = window_ / 2;
  frames_ = x.size() >= window_ ? (x.size() - window_) / hop_ + 1 : 1;
  const double top = std::min(max_frequency, 0.49 * fs);
  for (double z = bark(20); z <= bark(top) + 1e-9; z += 0.5) {
    // Invert the Bark formula by bisection.
    double lo = 0, hi = fs;
    for (int i = 0; i < 60; ++i) (bark(0.5 * (lo + hi)) < z ? lo : hi) = 0.5 * (lo + hi);
    edges_.push_back(0.5 * (lo + hi));
  }
  if (edges_.size() < 2) edges_ = {20, top};
  for (std::size_t b = 0; b + 1 < edges_.size(); ++b)
    threshold_.push_back(std::pow(10.0, threshold_db(std::sqrt(edges_[b] * edges_[b + 1])) / 10));

  noise_.assign(bands(), 0.0);
  const std::vector<double> power = band_power(x);
  reference_ = std::max(*std::max_element(power.begin(), power.end()), 1e-300);
  to_loudness(power, loudness_);
}

std::vector<double> PsychoSpectrogram::band_power(std::span<const double> x) const {
  std::vector<double> w(window_), in(window_);
  double wsum2 = 0;
  for (std::size_t n = 0; n < window_; ++n) {
    w[n] = 0.5 - 0.5 * std::cos(2 * kPi * (double(n) + 0.5) / double(window_));
    wsum2 += w[n] * w[n];
  }
  std::vector<fftw_complex> out(window_ / 2 + 1);
  fftw_plan plan = fftw_plan_dft_r2c_1d(int(window_), in.data(), out.data(), FFTW_ESTIMATE);
  std::vector<double> power(frames_ * bands(), 0.0);
  const double bin = fs_ / double(window_);
  for (std::size_t m = 0; m < frames_; ++m) {
    for (std::size_t n = 0; n < window_; ++n) {
      const std::size_t i = m * hop_ + n;
      in[n] = i < x.size() ? x[i] * w[n] : 0.0;
    }
    fftw_execute(plan);
    std::size_t b = 0;
    for (std::size_t k = 1; k < out.size(); ++k) {
      const double f = double(k) * bin;
      while (b < bands() && f >= edges_[b + 1]) ++b;
      if (b >= bands()) break;
      if (f < edges_[0]) continue;
      power[m * bands() + b] +=
          2 * (out[k][0] * out[k][0] + out[k][1] * out[k][1]) / (double(window_) * wsum2);
    }
  }
  fftw_destroy_plan(plan);
  return power;
}

void PsychoSpectrogram::set_noise(std::span<const double> residual) {
  const std::vector<double> power = band_power(residual);
  std::vector<double> column(frames_);
  for (std::size_t b = 0; b < bands(); ++b) {
    for (std::size_t m = 0; m < frames_; ++m) column[m] = power[m * bands() + b];
    std::nth_element(column.begin(), column.begin() + long(frames_ / 2), column.end());
    noise_[b] = column[frames_ / 2];
  }
}

void PsychoSpectrogram::to_loudness(const std::vector<double>& power,
                                    std::vector<float>& out) const {
  out.resize(power.size());
  for (std::size_t i = 0; i < power.size(); ++i) {
    const double tq = threshold_[i % bands()];
    const double e = power[i] / reference_ * 1e9;  // the reference at 90 dB SPL
    const double n = 0.08 * std::pow(tq, 0.23) * (std::pow(0.5 + 0.5 * e / tq, 0.23) - 1);
    out[i] = static_cast<float>(std::max(n, 0.0));
  }
}

std::vector<float> PsychoSpectrogram::of_partials(std::span<const Partial> partials) const {
  std::vector<double> power(frames_ * bands());
  for (std::size_t i = 0; i < power.size(); ++i) power[i] = noise_[i % bands()];
  const double bin = fs_ / double(window_);
  const double M = double(window_);
  for (const Partial& p : partials) {
    if (!(p.frequency > edges_.front() - 4 * bin) || p.frequency > edges_.back() + 4 * bin)
      continue;
    // The window's weighting of a decaying power: kappa = sum w^2 e^{-2 d tau} / sum w^2, in
    // closed form for the Hann window's square through its cosine terms is not worth it: sample.
    double kappa_num = 0, kappa_den = 0;
    for (int s = 0; s < 32; ++s) {
      const double u = (s + 0.5) / 32;
      const double w = 0.5 - 0.5 * std::cos(2 * kPi * u);
      kappa_num += w * w * std::exp(-2 * p.decay * (u - 0.5) * M / fs_);
      kappa_den += w * w;
    }
    const double kappa = kappa_num / kappa_den;
    // Band shares of the window's kernel around the partial.
    const double centre = p.frequency / bin;
    double share[16];
    std::size_t band_of[16];
    int used = 0;
    std::size_t b = 0;
    for (int k = int(std::floor(centre)) - 7; k <= int(std::floor(centre)) + 8; ++k) {
      const double f = double(k) * bin;
      if (k < 1 || f < edges_.front()) continue;
      while (b < bands() && f >= edges_[b + 1]) ++b;
      if (b >= bands()) break;
      share[used] = hann_kernel(double(k) - centre);
      band_of[used++] = b;
    }
    const double a2 = 0.5 * p.amplitude * p.amplitude * kappa;
    const double step = std::exp(-2 * p.decay * double(hop_) / fs_);
    double level = a2 * std::exp(-2 * p.decay * 0.5 * M / fs_);
    for (std::size_t m = 0; m < frames_ && level > 1e-16 * reference_; ++m, level *= step)
      for (int q = 0; q < used; ++q) power[m * bands() + band_of[q]] += level * share[q];
  }
  std::vector<float> out;
  to_loudness(power, out);
  return out;
}

double PsychoSpectrogram::difference(std::span<const float> other) const {
  double sum = 0;
  for (std::size_t i = 0; i < loudness_.size() && i < other.size(); ++i) {
    const double e = double(loudness_[i]) - double(other[i]);
    sum += e * e;
  }
  return sum;
}

double match_ratio(std::span<const Partial> a, std::span<const Partial> b, double duration) {
  if (a.empty() || b.empty()) return 0.0;
  std::vector<double> zb(b.size()), tb(b.size()), pb(b.size());
  for (std::size_t j = 0; j < b.size(); ++j) {
    zb[j] = bark(b[j].frequency);
    tb[j] = std::log(1 / std::clamp(b[j].decay, 0.01 / duration, 1e4));
    pb[j] = prominence(b[j], duration);
  }
  const double ln2 = std::log(2.0);
  double num = 0, den = 0;
  for (const Partial& p : a) {
    const double z = bark(p.frequency);
    const double t = std::log(1 / std::clamp(p.decay, 0.01 / duration, 1e4));
    double s1 = 0, s2 = 0;
    for (std::size_t j = 0; j < b.size(); ++j) {
      const double dz = (z - zb[j]) / 0.5, dt = (t - tb[j]) / ln2;
      const double k = std::exp(-0.5 * (dz * dz + dt * dt));
      s1 += pb[j] * k * k;  // u_ij = prominence_j * k_ij
      s2 += pb[j] * k;
    }
    const double w = prominence(p, duration);
    num += w * (s2 > 0 ? s1 / s2 : 0.0);
    den += w;
  }
  return den > 0 ? num / den : 0.0;
}

double match_ratio_product(std::span<const Partial> a, std::span<const Partial> b,
                           double duration) {
  return -match_ratio(a, b, duration) * match_ratio(b, a, duration);
}

double hybrid_metric(double psycho, double mrp) {
  return psycho / std::max(std::abs(mrp), 1e-6);
}

}  // namespace chladni::estimate
