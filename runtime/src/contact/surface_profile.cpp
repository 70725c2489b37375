#include "chladni/runtime/contact/surface_profile.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "../real_fft.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/random.hpp"

namespace chladni::runtime {
namespace {

// Samples per shortest wavelength: linear interpolation between them leaves the table's own
// images at 8 v / shortest - f, far above the band and far below it in level.
constexpr double kSamplesPerShortest = 8;
// The loop holds at least this many of the longest wavelengths, so its period is not heard as
// one at the slow speeds where that wavelength is audible.
constexpr double kLongestPerLoop = 8;
constexpr std::size_t kMinSamples = std::size_t{1} << 14, kMaxSamples = std::size_t{1} << 20;

void check(bool ok, const std::string& what) {
  if (!ok) throw InputError("roughness: " + what);
}

}  // namespace

const std::vector<Roughness>& roughness_presets() {
  // Orders of magnitude, set by ear against the materials' impacts: polished metal and glass are
  // smooth and fine-grained (low level), wood and stone coarse. The patch is a small ball's Hertz
  // contact under a fraction of a newton (a 1 cm steel ball at 0.3 N: 55 um across), wider on
  // softer materials.
  static const std::vector<Roughness> presets = {
      {"steel", 0.05, 0.5e-6, 2.0, 1e-4, 1e-2, 1e-4},
      {"aluminium", 0.06, 0.8e-6, 2.0, 1e-4, 1e-2, 1.2e-4},
      {"glass", 0.02, 0.1e-6, 2.5, 5e-5, 5e-3, 6e-5},
      {"ceramic", 0.04, 0.5e-6, 2.2, 1e-4, 1e-2, 8e-5},
      {"wood", 0.15, 5e-6, 1.8, 2e-4, 3e-2, 5e-4},
      {"stone", 0.2, 10e-6, 1.6, 3e-4, 5e-2, 3e-4},
      {"plastic", 0.08, 1e-6, 2.0, 1.5e-4, 1.5e-2, 3e-4},
  };
  return presets;
}

const Roughness& roughness_preset(std::string_view name) {
  std::string known;
  for (const Roughness& r : roughness_presets()) {
    if (r.name == name) return r;
    known += (known.empty() ? "" : ", ") + r.name;
  }
  throw InputError("unknown surface '" + std::string(name) + "' (known: " + known + ")");
}

void validate_roughness(const Roughness& r) {
  check(std::isfinite(r.level) && r.level >= 0 && r.level <= 10, "level must lie in [0, 10]");
  check(std::isfinite(r.height) && r.height >= 0 && r.height <= 1e-2,
        "height must lie in [0, 0.01] m");
  check(std::isfinite(r.beta) && r.beta >= 0 && r.beta <= 4, "beta must lie in [0, 4]");
  check(std::isfinite(r.shortest) && r.shortest >= 1e-6, "shortest must be >= 1e-6 m");
  check(std::isfinite(r.longest) && r.longest > r.shortest && r.longest <= 1,
        "longest must lie in (shortest, 1] m");
  check(r.longest / r.shortest <= 4096, "longest / shortest must be <= 4096");
  check(std::isfinite(r.patch) && r.patch > 0 && r.patch <= 0.1, "patch must lie in (0, 0.1] m");
  check(std::isfinite(r.ribs) && (r.ribs == 0 || (r.ribs >= 2 * r.shortest && r.ribs <= 0.1)),
        "ribs must be 0 or lie in [2 shortest, 0.1] m");
  check(std::isfinite(r.rib_depth) && r.rib_depth >= 0 && r.rib_depth <= 100,
        "rib_depth must lie in [0, 100]");
}

SurfaceProfile::SurfaceProfile(const Roughness& r, uint64_t seed) : r_(r) {
  validate_roughness(r);
  n_ = kMinSamples;
  while (double(n_) < kSamplesPerShortest * kLongestPerLoop * r.longest / r.shortest) n_ *= 2;
  if (n_ > kMaxSamples) throw InternalError("surface profile table too long");
  dx_ = r.shortest / kSamplesPerShortest;
  length_ = double(n_) * dx_;
  const double dk = 1.0 / length_;
  const std::size_t first =
      std::max<std::size_t>(1, std::size_t(std::ceil(1.0 / (r.longest * dk))));
  const std::size_t last = std::min(n_ / 2 - 1, std::size_t(std::floor(1.0 / (r.shortest * dk))));
  k_top_ = double(last) * dk;
  // P(k) = c k^-beta over the bins, c making the variance sum to 1.
  double sum = 0;
  for (std::size_t m = first; m <= last; ++m) sum += std::pow(double(m) * dk, -r.beta) * dk;
  c_ = 1.0 / sum;
  levels_ = 1;
  while (k_top_ / std::ldexp(1.0, levels_) >= double(first) * dk) ++levels_;
  height_.assign((n_ + 1) * levels_, 0.0f);
  curvature_.assign((n_ + 1) * levels_, 0.0f);

  Rng rng(seed ^ 0x70f11e5eedull);
  std::vector<double> phase(last + 1);
  for (std::size_t m = first; m <= last; ++m) phase[m] = 2 * std::numbers::pi * rng.uniform();
  // The ribs: harmonics h of bin m0 (whole ribs in the loop), amplitude a / h^2, their rms
  // sqrt(sum (a/h^2)^2 / 2) = rib_depth.
  std::size_t rib_bin = 0, rib_harmonics = 0;
  if (r.ribs > 0 && r.rib_depth > 0) {
    rib_bin = std::max<std::size_t>(1, std::size_t(std::llround(length_ / r.ribs)));
    rib_harmonics = std::max<std::size_t>(1, last / rib_bin);
    double sum4 = 0;
    for (std::size_t h = 1; h <= rib_harmonics; ++h) sum4 += std::pow(double(h), -4);
    rib_k_ = double(rib_bin) * dk;
    rib_a_ = r.rib_depth * std::sqrt(2 / sum4);
  }
  RealFft fft(n_, true);
  for (int j = 0; j < levels_; ++j) {
    const double k_max = k_top_ / std::ldexp(1.0, j);
    for (int which = 0; which < 2; ++which) {
      std::fill(fft.spec.begin(), fft.spec.end(), kiss_fft_cpx{0, 0});
      for (std::size_t m = first; m <= last && double(m) * dk <= k_max * (1 + 1e-12); ++m) {
        const double k = double(m) * dk;
        // y = sum sqrt(2 P dk) cos(2 pi k s + phi): the inverse transform doubles bin m.
        double a = std::sqrt(2 * c_ * std::pow(k, -r.beta) * dk) / 2;
        if (which == 1) a *= -std::pow(2 * std::numbers::pi * k, 2) * patch_response(k);
        fft.spec[m] = {float(a * std::cos(phase[m])), float(a * std::sin(phase[m]))};
      }
      for (std::size_t h = 1; h <= rib_harmonics; ++h) {
        const std::size_t m = h * rib_bin;
        const double k = double(m) * dk;
        if (k > k_max * (1 + 1e-12) || m >= n_ / 2) break;
        double a = rib_amplitude(int(h)) / 2;  // a cosine of amplitude A: bin m holds A / 2
        if (which == 1) a *= -std::pow(2 * std::numbers::pi * k, 2) * patch_response(k);
        fft.spec[m].r += float(a);
      }
      fft.execute();
      float* row = (which == 0 ? height_ : curvature_).data() + (n_ + 1) * j;
      std::copy(fft.real.begin(), fft.real.end(), row);
      row[n_] = row[0];
    }
  }
}

double SurfaceProfile::psd(double k) const {
  const double dk = 1.0 / length_;
  return k >= 1.0 / r_.longest - dk && k <= k_top_ + dk ? c_ * std::pow(k, -r_.beta) : 0.0;
}

double SurfaceProfile::patch_response(double k) const {
  const double x = std::numbers::pi * k * r_.patch;
  return std::exp(-0.5 * x * x);
}

float SurfaceProfile::read(const std::vector<float>& table, double s, double speed,
                           double nyquist) const {
  // Level u keeps wavenumbers up to k_top / 2^u; the pair (floor u, floor u + 1) below Nyquist
  // at this speed, blended so the band moves smoothly with it.
  const double over = std::abs(speed) * k_top_ / (0.5 * nyquist);
  const double u = over > 1 ? std::log2(over) : 0.0;
  const int j = int(u);
  const float w = float(u - j);
  double x = s / dx_;
  x -= std::floor(x / double(n_)) * double(n_);
  std::size_t i = std::min(std::size_t(x), n_ - 1);
  const float f = float(x - double(i));
  auto at = [&](int level) {
    if (level >= levels_) return 0.0f;
    const float* row = table.data() + (n_ + 1) * level;
    return row[i] + f * (row[i + 1] - row[i]);
  };
  return (1 - w) * at(j) + w * at(j + 1);
}

}  // namespace chladni::runtime
