#include "estimate_plot.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chladni/core/damping.hpp"
#include "chladni/plot/figure.hpp"

namespace chladni::cli {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

}  // namespace

void write_estimate_plot(const EstimatePlot& p) {
  const double fs = p.recording->sample_rate, fmax = 0.5 * fs, fmin = 50;
  plot::Figure fig(1400, 1000, p.title);
  const std::vector<double> recorded(p.recording->samples.begin() + long(p.features->origin),
                                     p.recording->samples.end());
  const plot::Spectrogram a = plot::spectrogram(recorded, fs);
  const plot::Spectrogram b = plot::spectrogram(p.resynthesized, fs);
  const double top = a.max_db();  // one scale for both, so levels compare
  fig.spectrogram({90, 70, 520, 380}, a, "recorded (from the strike)", fmin, fmax, top);
  fig.spectrogram({790, 70, 520, 380}, b, "resynthesized", fmin, fmax, top);

  double lo = 1e9, hi = 0, zlo = 1e9, zhi = 0;
  for (const auto* set : p.pooled)
    for (const auto& f : set->features) {
      lo = std::min(lo, f.frequency), hi = std::max(hi, f.frequency);
      const double z = f.damping_ratio();
      if (z > 0) zlo = std::min(zlo, z), zhi = std::max(zhi, z);
    }
  lo = std::max(20.0, std::pow(10.0, std::floor(std::log10(lo / 1.5))));
  hi = std::min(fmax, std::pow(10.0, std::ceil(std::log10(hi * 1.5))));
  zlo = std::pow(10.0, std::floor(std::log10(zlo / 3)));
  zhi = std::pow(10.0, std::ceil(std::log10(zhi * 3)));
  fig.panel({90, 560, 1220, 370}, {"frequency (Hz)", lo, hi, true},
            {"damping ratio d / omega", zlo, zhi, true}, "partials and damping curves");
  const plot::Colour blue{0.12, 0.47, 0.71}, red{0.84, 0.15, 0.16}, green{0.17, 0.63, 0.17};
  std::vector<double> x, y, ylo, yhi;
  for (const auto* set : p.pooled)
    for (const auto& f : set->features) {
      const double w = kTwoPi * f.frequency;
      x.push_back(f.frequency);
      y.push_back(f.decay / w);
      ylo.push_back((f.decay - f.decay_sigma) / w);
      yhi.push_back((f.decay + f.decay_sigma) / w);
    }
  fig.points(x, y, ylo, yhi, blue, "partials (1-sigma bars)");
  std::vector<double> cf, cz;
  damping_ratio_curve(p.curve, lo, hi, 200, cf, cz);
  fig.line(cf, cz, red, "through the partials: " + p.curve.to_string());
  if (p.material) {
    std::vector<double> mf, mz;
    damping_ratio_curve(*p.material, lo, hi, 200, mf, mz);
    fig.line(mf, mz, green, "the fitted material's: " + p.material->to_string(), 1.5);
  }
  fig.write_png(p.path);
}

}  // namespace chladni::cli
