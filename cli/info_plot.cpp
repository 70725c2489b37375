#include "info_plot.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "chladni/core/damping.hpp"
#include "chladni/plot/figure.hpp"
#include "chladni/report/bank_facts.hpp"
#include "chladni/report/radiation.hpp"

namespace chladni::cli {
namespace {

// Log-axis bounds around the positive values of v, widened by `pad` and rounded out to 1, 2 or
// 5 x 10^k.
std::pair<double, double> log_bounds(const std::vector<double>& v, double pad) {
  double lo = INFINITY, hi = 0;
  for (double x : v)
    if (x > 0 && std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
  if (!(hi > 0)) return {1e-4, 1e-1};
  lo /= pad, hi *= pad;
  const double el = std::pow(10.0, std::floor(std::log10(lo)));
  const double eh = std::pow(10.0, std::floor(std::log10(hi)));
  double a = el, b = 10 * eh;
  for (double m : {5.0, 2.0, 1.0})
    if (m * el <= lo) {
      a = m * el;
      break;
    }
  for (double m : {1.0, 2.0, 5.0})
    if (m * eh >= hi) {
      b = m * eh;
      break;
    }
  return {a, b};
}

}  // namespace

void write_info_plot(const std::string& path, const std::string& bank_path, const Soundbank& b) {
  const ModalModel model = to_modal_model(b, bank_path);
  const std::size_t n = model.mode_count();
  std::vector<double> f(n), zeta(n);
  for (std::size_t i = 0; i < n; ++i) {
    const report::ModeFacts facts = report::mode_facts(b, i);
    f[i] = facts.frequency_hz;
    zeta[i] = facts.damping_ratio;
  }
  plot::Figure fig(1200, 980, bank_path + ": " + std::to_string(n) + " modes, " + b.material.name);
  const auto [flo, fhi] = log_bounds(f, 1.2);
  const auto [zlo, zhi] = log_bounds(zeta, 2);
  const plot::Colour blue{0.12, 0.47, 0.71}, red{0.84, 0.15, 0.16}, grey{0.55, 0.55, 0.55},
      green{0.17, 0.63, 0.17}, orange{1.0, 0.5, 0.05};
  fig.panel({100, 70, 1040, 360}, {"frequency (Hz)", flo, fhi, true},
            {"damping ratio d / omega", zlo, zhi, true}, "damping per mode");
  fig.points(f, zeta, {}, {}, blue, "modes");
  std::vector<double> cf, cz;
  damping_ratio_curve(b.material.damping, flo, fhi, 300, cf, cz);
  fig.line(cf, cz, red, "material: " + b.material.damping.to_string());

  const std::vector<double> rad = report::radiation_at_1m(model);
  std::vector<double> db(n);
  double dlo = INFINITY, dhi = -INFINITY;
  for (std::size_t i = 0; i < n; ++i) {
    db[i] = rad[i] > 0 ? 20 * std::log10(rad[i]) : NAN;
    if (std::isfinite(db[i])) dlo = std::min(dlo, db[i]), dhi = std::max(dhi, db[i]);
  }
  if (!std::isfinite(dlo)) dlo = -100, dhi = 0;
  dlo = 10 * std::floor(dlo / 10 - 0.5), dhi = 10 * std::ceil(dhi / 10 + 0.5);
  fig.panel({100, 530, 1040, 360}, {"frequency (Hz)", flo, fhi, true},
            {"radiation at 1 m (dB re 1 Pa s^2 per unit modal acceleration)", dlo, dhi, false},
            "transfer level per mode (rms over directions)");
  // One series per source of the gain, so the legend says which modes fell back.
  const char* names[] = {"equivalent sources", "boundary elements", "poor fit (held-out > 30%)",
                         "compact-source estimate (no usable transfer)", "time-domain wave solve"};
  const plot::Colour colours[] = {blue, green, red, grey, orange};
  for (int kind = 0; kind < 5; ++kind) {
    std::vector<double> x, y;
    for (std::size_t i = 0; i < n; ++i) {
      int k = 3;
      if (b.transfer && b.transfer->usable(i)) {
        const TransferMethod m = b.transfer->modes[i].method;
        k = b.transfer->poor(i)         ? 2
            : m == TransferMethod::Bem  ? 1
            : m == TransferMethod::Wave ? 4
                                        : 0;
      }
      if (k == kind) x.push_back(f[i]), y.push_back(db[i]);
    }
    if (!x.empty()) fig.points(x, y, {}, {}, colours[kind], names[kind]);
  }
  fig.write_png(path);
}

}  // namespace chladni::cli
