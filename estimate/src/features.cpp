#include "chladni/estimate/features.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <optional>
#include <thread>

#include "chladni/core/error.hpp"
#include "chladni/runtime/thread_pool.hpp"
#include "mode_track.hpp"

namespace chladni::estimate {
namespace {

using cd = std::complex<double>;

// Start of the analysis: the largest sample, or, when the strike was clipped (three or more
// samples at the largest magnitude), the sample after the last clipped one, where the partials
// are again what the object did.
std::size_t peak_index(std::span<const double> x) {
  std::size_t at = 0;
  for (std::size_t i = 1; i < x.size(); ++i)
    if (std::abs(x[i]) > std::abs(x[at])) at = i;
  const double peak = std::abs(x[at]);
  std::size_t count = 0, last = at;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::abs(x[i]) >= peak * (1 - 1e-6)) ++count, last = i;
  return count >= 3 && last + 1 < x.size() ? last + 1 : at;
}

// The magnitude spectrum of r under a falling half-Hann window over its first L samples: full
// weight where the strike is loudest, tapered where it has decayed.
struct LongSpectrum {
  std::vector<double> mag;
  double bin_hz = 0;         ///< spacing of mag
  double resolution_hz = 0;  ///< fs / L
  double window_power = 0;   ///< sum of w^2
};

// The long spectrum's buffers, window and FFT plan, made once per analysis.
class LongTransform {
 public:
  LongTransform(std::size_t L) : L_(L) {
    while (n_ < L) n_ <<= 1;  // bins finer than fs / L: the fit refines the frequency
    in_.assign(n_, 0.0);
    out_.resize(n_ / 2 + 1);
    window_.resize(L);
    for (std::size_t i = 0; i < L; ++i) {
      const double c = std::cos(std::numbers::pi * 0.5 * double(i) / double(L));
      window_[i] = c * c;
      power_ += window_[i] * window_[i];
    }
    plan_ = fftw_plan_dft_r2c_1d(int(n_), in_.data(), reinterpret_cast<fftw_complex*>(out_.data()),
                                 FFTW_ESTIMATE);
  }
  ~LongTransform() { fftw_destroy_plan(plan_); }
  LongTransform(const LongTransform&) = delete;
  LongTransform& operator=(const LongTransform&) = delete;

  void of(const std::vector<double>& r, double fs, LongSpectrum& s) {
    for (std::size_t i = 0; i < L_; ++i) in_[i] = r[i] * window_[i];
    fftw_execute(plan_);
    s.mag.resize(n_ / 2 + 1);
    for (std::size_t k = 0; k < s.mag.size(); ++k) s.mag[k] = std::sqrt(std::norm(out_[k]));
    s.bin_hz = fs / double(n_);
    s.resolution_hz = fs / double(L_);
    s.window_power = power_;
  }

 private:
  std::size_t L_, n_ = 1;
  double power_ = 0;
  std::vector<double> in_, window_;
  std::vector<cd> out_;  // std::complex is layout-compatible with fftw_complex
  fftw_plan plan_;
};

// Median of v[lo, hi).
double median_of(const std::vector<double>& v, std::size_t lo, std::size_t hi) {
  if (hi <= lo) return 0;
  std::vector<double> part(v.begin() + long(lo), v.begin() + long(hi));
  std::nth_element(part.begin(), part.begin() + long(part.size() / 2), part.end());
  return part[part.size() / 2];
}

struct Candidate {
  double frequency, magnitude, noise_sigma;
};

// Up to `count` peaks standing min_snr over the local floor (the median over a third of an
// octave each side), outside the excluded zones.
struct Zone {
  double centre, half_width;
};

std::vector<Candidate> pick_peaks(const LongSpectrum& s, double fmin, double fmax, double snr,
                                  const std::vector<Zone>& excluded, std::size_t count) {
  const std::size_t lo = std::max<std::size_t>(2, std::size_t(fmin / s.bin_hz));
  const std::size_t hi = std::min(s.mag.size() - 2, std::size_t(fmax / s.bin_hz));
  std::vector<std::size_t> maxima;
  for (std::size_t k = lo; k < hi; ++k)
    if (s.mag[k] > s.mag[k - 1] && s.mag[k] >= s.mag[k + 1]) maxima.push_back(k);
  // The floor: medians over a third of an octave each side, every sixth of an octave.
  std::vector<double> centre, level;
  for (double f = std::max(fmin, 4 * s.bin_hz); f < fmax * 1.12; f *= std::pow(2.0, 1.0 / 6)) {
    const std::size_t w = std::max<std::size_t>(8, std::size_t(f * 0.26 / s.bin_hz));
    const std::size_t k = std::size_t(f / s.bin_hz);
    centre.push_back(std::log(f));
    level.push_back(median_of(s.mag, k > w ? k - w : 1, std::min(s.mag.size(), k + w + 1)));
  }
  auto floor_at = [&](double f) {
    const double lf = std::log(f);
    std::size_t i = 0;
    while (i + 2 < centre.size() && centre[i + 1] < lf) ++i;
    if (centre.size() < 2) return level.empty() ? 0.0 : level[0];
    const double u = std::clamp((lf - centre[i]) / (centre[i + 1] - centre[i]), 0.0, 1.0);
    return level[i] * (1 - u) + level[i + 1] * u;
  };
  // Clearest first (height over the local floor), so that a weak low partial standing well
  // clear of the noise is taken before the skirts of a loud one.
  std::vector<double> clarity(s.mag.size(), 0.0);
  for (std::size_t k : maxima)
    clarity[k] = s.mag[k] / std::max(floor_at(double(k) * s.bin_hz), 1e-300);
  std::sort(maxima.begin(), maxima.end(),
            [&](std::size_t a, std::size_t b) { return clarity[a] > clarity[b]; });
  std::vector<Candidate> out;
  const double zone = 3 * s.resolution_hz;
  for (std::size_t k : maxima) {
    if (out.size() >= count) break;
    // Parabolic interpolation of the log magnitude.
    const double a = std::log(s.mag[k - 1] + 1e-300), b = std::log(s.mag[k]),
                 c = std::log(s.mag[k + 1] + 1e-300);
    const double den = a - 2 * b + c;
    const double f = (double(k) + (den < 0 ? 0.5 * (a - c) / den : 0.0)) * s.bin_hz;
    if (std::any_of(excluded.begin(), excluded.end(),
                    [&](const Zone& z) { return std::abs(z.centre - f) < z.half_width; }))
      continue;
    if (std::any_of(out.begin(), out.end(),
                    [&](const Candidate& o) { return std::abs(o.frequency - f) < zone; }))
      continue;
    const double floor = floor_at(f);
    if (s.mag[k] < floor * std::pow(10.0, snr / 20)) continue;
    // White noise of deviation sigma gives a median magnitude of 0.8326 sigma sqrt(sum w^2).
    out.push_back({f, s.mag[k], floor / (0.8326 * std::sqrt(s.window_power))});
  }
  return out;
}

double energy(const std::vector<double>& v) {
  double e = 0;
  for (double x : v) e += x * x;
  return e;
}

// The round's candidates, fitted on all threads against the same residual (unset: no fit).
std::vector<std::optional<Feature>> fit_all(runtime::ThreadPool& pool,
                                            const std::vector<Candidate>& peaks,
                                            const std::vector<double>& r, double fs,
                                            const HannWindows& windows) {
  struct Job {
    const std::vector<Candidate>* peaks;
    const std::vector<double>* r;
    const HannWindows* windows;
    double fs;
    std::vector<std::optional<Feature>> fits;
  } job{&peaks, &r, &windows, fs, std::vector<std::optional<Feature>>(peaks.size())};
  pool.run(
      [](void* ctx, int i) {
        auto& j = *static_cast<Job*>(ctx);
        const Candidate& c = (*j.peaks)[std::size_t(i)];
        Feature f;
        if (fit_partial(*j.r, j.fs, c.frequency, c.noise_sigma, *j.windows, f))
          j.fits[std::size_t(i)] = f;
      },
      &job, int(peaks.size()));
  return std::move(job.fits);
}

// The residual and its energy; a partial is taken when subtracting it lowers that energy.
struct Residual {
  std::vector<double> r, trial;
  double total = 0, left = 0;

  bool take(Feature& f, double fs) {
    trial.assign(r.begin(), r.end());  // reuses its storage: no page faults per candidate
    subtract_partial(trial, fs, f);
    const double after = energy(trial);
    if (!(after < left)) return false;  // the fit did not describe what is there
    f.energy_share = (left - after) / total;
    std::swap(r, trial);
    left = after;
    return true;
  }
};

}  // namespace

double Feature::damping_ratio() const {
  return frequency > 0 ? decay / (2 * std::numbers::pi * frequency) : 0.0;
}

FeatureSet extract_features(std::span<const double> x, double fs, const FeatureOptions& o) {
  if (!(fs > 0) || !std::isfinite(fs)) throw InputError("features: sample rate must be > 0");
  if (!(o.explained > 0 && o.explained <= 1))
    throw InputError("features: the share to explain must lie in (0, 1]");
  const double fmax = o.max_frequency > 0 ? std::min(o.max_frequency, 0.49 * fs) : 0.45 * fs;
  if (!(o.min_frequency >= 0) || !(o.min_frequency < fmax))
    throw InputError("features: the frequency range is empty");
  FeatureSet set;
  set.sample_rate = fs;
  if (x.empty()) return set;
  set.origin = peak_index(x);
  Residual res;
  res.r.assign(x.begin() + long(set.origin), x.end());
  set.duration = double(res.r.size()) / fs;
  res.total = res.left = energy(res.r);
  if (!(res.total > 0)) {
    set.residual = std::move(res.r);
    return set;
  }
  // Long enough to separate partials a few Hz apart, short enough to stay on the sound.
  const std::size_t L = std::min(res.r.size(), std::size_t(std::lround(4.0 * fs)));
  LongTransform transform(L);
  LongSpectrum s;
  const HannWindows windows(fs);
  runtime::ThreadPool pool(o.threads > 0 ? o.threads
                                         : int(std::max(1u, std::thread::hardware_concurrency())));
  std::vector<Zone> excluded;
  const double tried_zone = 3 * fs / double(L);
  auto own_zone = [&](const Feature& g) { return std::max(tried_zone, 2 * fs / double(g.window)); };
  auto done = [&] {
    return set.features.size() >= o.max_features ||
           (1 - res.left / res.total >= o.explained && set.features.size() >= o.min_features);
  };
  int idle_rounds = 0;
  for (std::size_t round = 0; round < 4 * o.max_features && !done(); ++round) {
    transform.of(res.r, fs, s);
    const auto peaks = pick_peaks(s, o.min_frequency, fmax, o.min_snr_db, excluded, 8);
    if (peaks.empty() || idle_rounds >= 3) break;
    const std::size_t before = set.features.size();
    auto fits = fit_all(pool, peaks, res.r, fs, windows);
    for (std::size_t i = 0; i < peaks.size() && !done(); ++i) {
      excluded.push_back({peaks[i].frequency, tried_zone});
      if (!fits[i]) continue;
      Feature& f = *fits[i];
      // A fit within two bins (of its own frame) of a partial already taken is what that
      // partial's subtraction left, not a new one; a decay less certain than itself is noise.
      const bool taken = std::any_of(set.features.begin(), set.features.end(), [&](const auto& g) {
        return std::abs(g.frequency - f.frequency) < own_zone(g);
      });
      if (taken || f.decay_sigma > f.decay + 0.5) {
        excluded.push_back({f.frequency, tried_zone});
        continue;
      }
      if (!res.take(f, fs)) continue;
      set.features.push_back(f);
      excluded.push_back({f.frequency, own_zone(f)});
    }
    // Three rounds that found nothing new: what stands out is not partials.
    idle_rounds = set.features.size() > before ? 0 : idle_rounds + 1;
  }
  std::sort(set.features.begin(), set.features.end(),
            [](const Feature& a, const Feature& b) { return a.frequency < b.frequency; });
  set.explained = 1 - res.left / res.total;
  set.residual = std::move(res.r);
  return set;
}

std::vector<double> synthesize(const std::vector<Feature>& features, double fs,
                               std::size_t frames) {
  std::vector<double> out(frames, 0.0);
  for (const Feature& f : features) add_partial(out, fs, f, 1.0);
  return out;
}

}  // namespace chladni::estimate
