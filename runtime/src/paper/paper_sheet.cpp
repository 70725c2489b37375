#include "chladni/runtime/paper/paper_sheet.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/runtime/phisem/phisem.hpp"

namespace chladni::runtime {

using std::numbers::pi;

double sheet_radius(double b, const PaperMaterial& material) {
  // Arc of angle phi with chord / arc = sin(phi/2) / (phi/2) = chord_ratio: bisection on x=phi/2.
  const double c = material.chord_ratio;
  if (!(c > 0 && c < 1)) return 0;  // flat
  double lo = 1e-9, hi = pi;
  for (int i = 0; i < 60; ++i) {
    const double x = 0.5 * (lo + hi);
    (std::sin(x) / x > c ? lo : hi) = x;
  }
  return b / (2 * lo);
}

std::vector<SheetMode> sheet_modes(double a, double b, double R, const PaperMaterial& mat,
                                   double min_hz, double max_hz) {
  if (!(a > 0 && b > 0) || !std::isfinite(a) || !std::isfinite(b)) {
    throw InputError("sheet_modes: sheet size " + std::to_string(a) + " x " + std::to_string(b) +
                     " m must be positive");
  }
  const double rho_h = mat.surface_density;
  const double rho = rho_h / mat.thickness;
  const double D = mat.young * std::pow(mat.thickness, 3) / (12 * (1 - mat.poisson * mat.poisson));
  const double bend = D / rho_h;
  const double membrane = R > 0 ? mat.young / (rho * R * R) : 0;
  const double wmax = 2 * pi * max_hz, wmin = 2 * pi * min_hz;
  std::vector<SheetMode> out;
  // Bending alone bounds k^2 = kx^2 + ky^2 <= wmax / sqrt(bend): the loops stop there.
  const double kmax2 = wmax / std::sqrt(bend);
  for (int m = 1; m * pi / a <= std::sqrt(kmax2) && m < 65536; ++m) {
    const double kx = m * pi / a;
    for (int n = 1; n < 65536; ++n) {
      const double ky = n * pi / b;
      const double k2 = kx * kx + ky * ky;
      if (k2 > kmax2) break;
      const double w2 = bend * k2 * k2 + membrane * std::pow(kx, 4) / (k2 * k2);
      const double w0 = std::sqrt(w2);
      if (w0 > wmax || w0 < wmin) continue;
      const double decay = 0.5 * mat.loss_factor * w0 + mat.air_decay;
      if (decay >= w0) continue;  // overdamped: no ring
      out.push_back({std::sqrt(w2 - decay * decay), decay, static_cast<std::uint16_t>(m),
                     static_cast<std::uint16_t>(n), 1.0f});
    }
  }
  std::sort(out.begin(), out.end(),
            [](const SheetMode& x, const SheetMode& y) { return x.omega < y.omega; });
  return out;
}

std::vector<SheetMode> thin_modes(const std::vector<SheetMode>& modes, std::size_t count) {
  if (modes.size() <= count || count == 0) return modes;
  // Log-frequency bands, one kept mode (the band's middle one) per non-empty band.
  const double lo = std::log(modes.front().omega), hi = std::log(modes.back().omega) + 1e-9;
  std::vector<SheetMode> out;
  std::size_t begin = 0;
  for (std::size_t band = 0; band < count && begin < modes.size(); ++band) {
    const double edge = lo + (hi - lo) * double(band + 1) / double(count);
    std::size_t end = begin;
    while (end < modes.size() && std::log(modes[end].omega) < edge) ++end;
    if (end == begin) continue;
    double weight2 = 0;
    for (std::size_t i = begin; i < end; ++i) weight2 += double(modes[i].weight) * modes[i].weight;
    SheetMode kept = modes[begin + (end - begin) / 2];
    kept.weight = static_cast<float>(std::sqrt(weight2));
    out.push_back(kept);
    begin = end;
  }
  return out;
}

double sheet_mode_shape(const SheetMode& mode, double u, double v) {
  return std::sin(mode.m * pi * u) * std::sin(mode.n * pi * v);
}

std::vector<CrumpleImpulse> crumple_burst(Rng& rng) {
  // One shake of the PhISEM "paper" instrument (phisem.hpp): collisions at its rate while the
  // system energy decays, each as strong as the energy then, in either direction.
  static const PhisemParams paper = phisem_params(phisem_preset("paper"), kPhisemReferenceRate);
  std::vector<CrumpleImpulse> out;
  for (const PhisemCollision& c : phisem_collisions(paper, static_cast<uint32_t>(rng.next()), 1)) {
    const double sign = rng.uniform() < 0.5 ? -1.0 : 1.0;
    const double u = rng.uniform(), v = rng.uniform();
    out.push_back({c.sample / kPhisemReferenceRate, kClickScale * sign * c.energy, u, v});
  }
  if (out.empty()) out.push_back({0, kClickScale, 0.5, 0.5});  // a crumple always clicks
  // The snap itself: the strongest click comes first.
  out.front().time = 0;
  out.front().strength = std::copysign(2.0 + std::abs(out.front().strength), out.front().strength);
  return out;
}

}  // namespace chladni::runtime
