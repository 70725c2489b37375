#include "mode_track.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace chladni::estimate {
namespace {

using cd = std::complex<double>;
constexpr double kTwoPi = 2 * std::numbers::pi;

// r demodulated by e^{-i omega n}, extended only as far as the frames reach; the phasor is
// renewed exactly every 1024 samples.
class Demodulated {
 public:
  Demodulated(const std::vector<double>& r, double omega)
      : r_(r), omega_(omega), step_(std::polar(1.0, -omega)) {}
  const cd* upto(std::size_t end) {
    for (std::size_t n = z_.size(); n < end; ++n) {
      if ((n & 1023) == 0) ph_ = std::polar(1.0, -omega_ * double(n));
      z_.push_back(r_[n] * ph_);
      ph_ *= step_;
    }
    return z_.data();
  }

 private:
  const std::vector<double>& r_;
  double omega_;
  cd step_, ph_ = 1.0;
  std::vector<cd> z_;
};

struct Line {
  double slope = 0, intercept = 0, slope_sigma = 0;
};

// Weighted least squares y = a + b t; the slope's standard error from the weighted residuals.
Line fit_line(const std::vector<double>& t, const std::vector<double>& y,
              const std::vector<double>& w) {
  double sw = 0, st = 0, sy = 0;
  for (std::size_t i = 0; i < t.size(); ++i) sw += w[i], st += w[i] * t[i], sy += w[i] * y[i];
  const double tm = st / sw, ym = sy / sw;
  double stt = 0, sty = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    stt += w[i] * (t[i] - tm) * (t[i] - tm);
    sty += w[i] * (t[i] - tm) * (y[i] - ym);
  }
  Line l;
  l.slope = sty / stt;
  l.intercept = ym - l.slope * tm;
  double ss = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double e = y[i] - l.intercept - l.slope * t[i];
    ss += w[i] * e * e;
  }
  // Hann frames overlapping by 3/4 share their noise (correlation 0.66, 0.17 and 0.01 at lags
  // 1-3, Harris 1978), which inflates the slope's variance by up to 1 + 2 sum rho = 2.67.
  l.slope_sigma = std::sqrt(2.67 * ss / std::max(double(t.size()) - 2, 1.0) / stt);
  return l;
}

struct Track {
  Feature f;
  double score = INFINITY;
};

// One frame length M (Hann, hop M/4) of r demodulated at omega: the frames from the start while
// the partial stands 12 dB above the noise (where ln|S + N| is still nearly unbiased) and at most
// 80 dB down (256 at most), then the two
// line fits, each frame weighted by its signal-to-noise ratio squared (the inverse variance of
// ln|X| and of arg X) with a floor for what noise does not explain (beats with neighbours).
bool fit_at(const std::vector<double>& r, double fs, double omega, double noise_sigma,
            const std::vector<double>& w, Demodulated& demod, Track& out) {
  const std::size_t M = w.size(), hop = M / 4;
  if (r.size() < M + 3 * hop) return false;
  const double wsum2 = 0.375 * double(M);  // sum of a periodic Hann window's squares
  const double noise = noise_sigma * std::sqrt(wsum2);
  const double floor = 4 * noise;
  std::vector<double> t, mag, ph, weight;
  double first = 0;
  // 256 frames fix a decay well; a longer frame length sees further if the partial rings on.
  for (std::size_t s = 0; s + M <= r.size() && t.size() < 256; s += hop) {
    const cd* z = demod.upto(s + M) + s;
    cd X = 0;
    for (std::size_t n = 0; n < M; ++n) X += w[n] * z[n];
    const double a = std::abs(X);
    if (t.empty()) first = a;
    if (!(a > floor) || a < first * 1e-4) break;
    t.push_back((double(s) + 0.5 * double(M)) / fs);
    weight.push_back(1.0 / (noise * noise / (a * a) + 1e-2));
    mag.push_back(std::log(a));
    double p = std::arg(X);
    if (!ph.empty()) p += kTwoPi * std::round((ph.back() - p) / kTwoPi);
    ph.push_back(p);
  }
  if (t.size() < 4) return false;
  const Line lm = fit_line(t, mag, weight), lp = fit_line(t, ph, weight);
  Feature& f = out.f;
  f.decay = std::max(-lm.slope, 0.0);
  f.decay_sigma = lm.slope_sigma;
  const double delta = lp.slope;  // rad/s
  f.frequency = (omega * fs + delta) / kTwoPi;
  f.frequency_sigma = lp.slope_sigma / kTwoPi;
  // (A/2) e^{i phi} = e^{c} / W(delta, d), W = sum_n w_n e^{(i delta - d)(n - M/2)/fs}.
  cd W = 0;
  const cd rate(-f.decay, delta);
  const cd step = std::exp(rate / fs);
  cd term = std::exp(rate * ((0.5 - 0.5 * double(M)) / fs));
  for (std::size_t n = 0; n < M; ++n, term *= step) W += w[n] * term;
  const cd half = std::exp(cd(lm.intercept, lp.intercept)) / W;
  f.amplitude = 2 * std::abs(half);
  f.phase = std::arg(half);
  f.window = M;
  f.frames = t.size();
  out.score = lm.slope_sigma;
  return std::isfinite(f.amplitude) && std::isfinite(f.frequency) && f.amplitude > 0;
}

}  // namespace

HannWindows::HannWindows(double fs) {
  std::size_t shortest = 256;
  while (double(shortest) < 0.0058 * fs) shortest <<= 1;
  for (std::size_t M = shortest; double(M) <= 0.75 * fs; M <<= 1) {
    std::vector<double> w(M);
    for (std::size_t n = 0; n < M; ++n)
      w[n] = 0.5 - 0.5 * std::cos(kTwoPi * (double(n) + 0.5) / double(M));
    windows_.push_back(std::move(w));
  }
}

bool fit_partial(const std::vector<double>& r, double fs, double frequency, double noise_sigma,
                 const HannWindows& windows, Feature& out) {
  // Every frame length, all at the peak's frequency.
  const double omega = kTwoPi * frequency / fs;
  Demodulated demod(r, omega);
  Track best;
  const std::vector<double>* chosen = nullptr;
  for (const std::vector<double>& w : windows.all()) {
    const std::size_t M = w.size();
    Track tr;
    if (!fit_at(r, fs, omega, noise_sigma, w, demod, tr)) continue;
    // A refined frequency more than half a bin away belongs to a neighbour.
    if (std::abs(kTwoPi * tr.f.frequency / fs - omega) > std::numbers::pi / double(M)) continue;
    if (tr.score < best.score) best = tr, chosen = &w;
  }
  if (!std::isfinite(best.score)) return false;
  // Again at the best frame length, demodulated at the refined frequency, when it moved by more
  // than a fiftieth of a bin (the window's response then no longer tilts the decay).
  const double refined = kTwoPi * best.f.frequency / fs;
  const std::size_t M = best.f.window;
  if (std::abs(refined - omega) > 0.02 * kTwoPi / double(M)) {
    Demodulated again(r, refined);
    Track tr;
    if (fit_at(r, fs, refined, noise_sigma, *chosen, again, tr)) best = tr;
  }
  out = best.f;
  return true;
}

void add_partial(std::vector<double>& r, double fs, const Feature& f, double gain) {
  const cd rate(-f.decay, kTwoPi * f.frequency);
  const cd step = std::exp(rate / fs);
  cd ph = 0;
  for (std::size_t n = 0; n < r.size(); ++n) {
    if ((n & 1023) == 0)  // renewed exactly, so rounding does not build up
      ph = gain * f.amplitude * std::exp(rate * (double(n) / fs) + cd(0, f.phase));
    r[n] += ph.real();
    ph *= step;
  }
}

}  // namespace chladni::estimate
