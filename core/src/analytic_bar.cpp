#include "chladni/core/analytic_bar.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "chladni/core/error.hpp"

namespace chladni {

double free_free_beta_l(int n) {
  // Newton on f(x) = cos x cosh x - 1 from the asymptote (2n + 1) pi / 2.
  double x = (2 * n + 1) * std::numbers::pi / 2;
  for (int it = 0; it < 50; ++it) {
    const double f = std::cos(x) * std::cosh(x) - 1.0;
    const double df = -std::sin(x) * std::cosh(x) + std::cos(x) * std::sinh(x);
    const double dx = f / df;
    x -= dx;
    if (std::abs(dx) < 1e-14 * x) break;
  }
  return x;
}

namespace {

// Free-free bending shape cosh + cos - sigma (sinh + sin), normalized so that
// integral_0^L phi^2 dx = L. sigma -> 1 for high modes, so cosh - sigma sinh is evaluated through
// 1 - sigma = (cos bl - sin bl - exp(-bl)) / (sinh bl - sin bl) to avoid cancellation.
double bending_shape(double beta, double L, double x) {
  const double bl = beta * L, bx = beta * x;
  const double one_minus_sigma =
      (std::cos(bl) - std::sin(bl) - std::exp(-bl)) / (std::sinh(bl) - std::sin(bl));
  const double sigma = 1.0 - one_minus_sigma;
  const double hyp = 0.5 * (std::exp(bx) * one_minus_sigma + std::exp(-bx) * (1.0 + sigma));
  return hyp + std::cos(bx) - sigma * std::sin(bx);
}

// Pressure at 1 m per unit modal acceleration, until acoustic transfer exists: the faces that the
// mode moves (area S, mean surface acceleration ~ qdd / sqrt(m)) radiate like a compact source,
// p ~ rho0 S a / (4 pi r), reduced by k a_eq for a dipole (a_eq: radius of a disc of area S).
double radiation_estimate(int kind, double omega, double L, double b, double h, double mass) {
  constexpr double rho0 = 1.204, c0 = 343.0;
  const double S = kind == 0 ? L * b : kind == 1 ? L * h : 2 * b * h;
  const double ka = omega / c0 * std::sqrt(S / std::numbers::pi);
  return rho0 * S / std::sqrt(mass) / (4 * std::numbers::pi) * std::min(1.0, ka);
}

}  // namespace

ModalModel analytic_bar(const BarSpec& bar, int stations) {
  if (!(bar.length > 0 && bar.width > 0 && bar.thickness > 0 && bar.youngs_modulus > 0 &&
        bar.density > 0) ||
      stations < 2) {
    throw InputError("analytic bar: dimensions, Young's modulus and density must be > 0");
  }
  const double L = bar.length, b = bar.width, h = bar.thickness, E = bar.youngs_modulus;
  const double rho = bar.density, A = b * h, mass = rho * A * L;
  const double wmax = 2 * std::numbers::pi * bar.max_frequency;

  struct Mode {
    double omega;
    int kind;  // 0: bending across z, 1: bending across y, 2: axial
    int n;
  };
  std::vector<Mode> modes;
  // A long or slender bar can have millions of modes below wmax; refuse before making them.
  constexpr std::size_t kMaxModes = 100000;
  const auto add = [&](const Mode& md) {
    if (modes.size() == kMaxModes)
      throw InputError("analytic bar: more than " + std::to_string(kMaxModes) + " modes below " +
                       std::to_string(int(bar.max_frequency)) +
                       " Hz (shorten the bar or lower max_frequency)");
    modes.push_back(md);
  };
  // Bending: omega = (beta_n)^2 sqrt(E I / (rho A)), I = b h^3 / 12 (z) or h b^3 / 12 (y).
  const double Iz = b * h * h * h / 12, Iy = h * b * b * b / 12;
  for (int kind = 0; kind < 2; ++kind) {
    const double c = std::sqrt(E * (kind == 0 ? Iz : Iy) / (rho * A));
    for (int n = 1;; ++n) {
      const double beta = free_free_beta_l(n) / L;
      const double w = beta * beta * c;
      if (w > wmax) break;
      add({w, kind, n});
    }
  }
  // Axial: omega = n pi / L sqrt(E / rho).
  for (int n = 1;; ++n) {
    const double w = n * std::numbers::pi / L * std::sqrt(E / rho);
    if (w > wmax) break;
    add({w, 2, n});
  }
  std::sort(modes.begin(), modes.end(),
            [](const Mode& a, const Mode& b) { return a.omega < b.omega; });

  ModalModel m;
  m.name = "analytic bar";
  for (int s = 0; s < stations; ++s) {
    m.points.push_back({L * s / (stations - 1), b / 2, h});
    m.normals.push_back({0, 0, 1});
  }
  // Mass normalization: integral rho A phi^2 dx = 1  =>  phi_hat = phi / sqrt(rho A L).
  const double norm = 1.0 / std::sqrt(mass);
  for (const Mode& md : modes) {
    m.omega.push_back(md.omega);
    m.decay.push_back(0.0);
    m.radiation.push_back(radiation_estimate(md.kind, md.omega, L, b, h, mass));
    for (const Vec3& p : m.points) {
      const double x = p[0];
      if (md.kind == 2) {
        // Axial: u = cos(n pi x / L), integral of u^2 = L / 2.
        m.shapes.push_back(
            {std::sqrt(2.0) * norm * std::cos(md.n * std::numbers::pi * x / L), 0, 0});
      } else {
        const double beta = free_free_beta_l(md.n) / L;
        const double phi = norm * bending_shape(beta, L, x);
        m.shapes.push_back(md.kind == 0 ? Vec3{0, 0, phi} : Vec3{0, phi, 0});
      }
    }
  }
  return m;
}

}  // namespace chladni
