// Analytic bar modes against the Euler-Bernoulli values of meshes/README.md, mass
// normalization, and the half-sine contact spectrum.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "chladni/core/analytic_bar.hpp"
#include "chladni/runtime/modal/contact_weight.hpp"

using namespace chladni;

namespace {
std::vector<double> hz(const ModalModel& m) {
  std::vector<double> out;
  for (double w : m.omega) out.push_back(w / (2 * std::numbers::pi));
  return out;
}
bool has_near(const std::vector<double>& v, double x, double tol) {
  for (double y : v) {
    if (std::abs(y - x) <= tol) return true;
  }
  return false;
}
}  // namespace

TEST(AnalyticBar, FreeFreeRootsAreKnownValues) {
  EXPECT_NEAR(free_free_beta_l(1), 4.730040745, 1e-8);
  EXPECT_NEAR(free_free_beta_l(2), 7.853204624, 1e-8);
  EXPECT_NEAR(free_free_beta_l(3), 10.995607838, 1e-8);
}

TEST(AnalyticBar, SteelAndAluminiumBarFrequenciesMatchTheReference) {
  BarSpec steel;  // 0.300 x 0.030 x 0.010 m, E 200 GPa, rho 7850
  const auto f = hz(analytic_bar(steel));
  for (double x : {576.5, 1589.1, 3115.3, 5149.8, 1729.5, 4767.0, 8412.6}) {
    EXPECT_TRUE(has_near(f, x, 0.1 + 1e-4 * x)) << x << " Hz missing";
  }
  BarSpec al;
  al.youngs_modulus = 70e9;
  al.poisson_ratio = 0.35;
  al.density = 2700;
  const auto g = hz(analytic_bar(al));
  for (double x : {581.5, 1603.1, 3142.6, 5194.9, 1744.6, 4809.0, 8486.3}) {
    EXPECT_TRUE(has_near(g, x, 0.1 + 1e-4 * x)) << x << " Hz missing";
  }
  EXPECT_TRUE(std::is_sorted(f.begin(), f.end()));
}

TEST(AnalyticBar, ShapesAreMassNormalized) {
  BarSpec steel;
  const ModalModel m = analytic_bar(steel, 2001);
  const double rhoA = steel.density * steel.width * steel.thickness;
  const double dx = steel.length / (m.points.size() - 1);
  for (std::size_t i = 0; i < m.mode_count(); ++i) {
    double integral = 0;  // trapezoid of rho A |phi|^2 along the bar
    for (std::size_t v = 0; v < m.points.size(); ++v) {
      const Vec3& s = m.shape(i, v);
      const double w = (v == 0 || v + 1 == m.points.size()) ? 0.5 : 1.0;
      integral += w * rhoA * (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) * dx;
    }
    EXPECT_NEAR(integral, 1.0, 1e-4) << "mode " << i;
  }
}

TEST(Impact, IdealImpulseWeighsEveryModeByJ) {
  const auto w = runtime::contact_weight(0.02, 0.0, 5000.0, 3.0);
  EXPECT_DOUBLE_EQ(w.real(), 0.02);
  EXPECT_DOUBLE_EQ(w.imag(), 0.0);
}

TEST(Impact, HalfSineClosedFormMatchesQuadratureAndFiltersHighModes) {
  const double J = 0.01, tau = 0.001;
  auto quad = [&](double wd, double d) {  // midpoint rule, very fine
    std::complex<double> s = 0;
    const int n = 200000;
    const double b = std::numbers::pi / tau;
    for (int k = 0; k < n; ++k) {
      const double t = (k + 0.5) * tau / n;
      s += 0.5 * J * b * std::sin(b * t) * std::exp(-std::complex<double>(-d, wd) * t);
    }
    return s * (tau / n);
  };
  for (double f : {50.0, 500.0, 499.9, 2000.0, 9000.0}) {  // 500 Hz = pi / tau: the 0/0 case
    const double wd = 2 * std::numbers::pi * f;
    const auto w = runtime::contact_weight(J, tau, wd, f == 500.0 ? 0.0 : 4.0);
    const auto q = quad(wd, f == 500.0 ? 0.0 : 4.0);
    EXPECT_NEAR(std::abs(w - q), 0.0, 1e-6 * J) << f << " Hz";
  }
  // A 1 ms contact passes low modes almost fully and removes most of the energy above 1/tau.
  EXPECT_GT(std::abs(runtime::contact_weight(J, tau, 2 * std::numbers::pi * 50, 1.0)), 0.95 * J);
  EXPECT_LT(std::abs(runtime::contact_weight(J, tau, 2 * std::numbers::pi * 5000, 1.0)), 0.05 * J);
}
