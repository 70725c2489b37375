// A thin rigid body in translation: an oblate spheroid of aspect 50 moving along its short axis.
// At low ka its far field is the potential-flow dipole (Lamb, Hydrodynamics, Art. 114); at ka
// 2-10 the time-domain path is checked against boundary elements on the same surface.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <vector>

#include "chladni/core/soundbank.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "fem_fixtures.hpp"

namespace chladni {
namespace {

using cd = std::complex<double>;
using precompute::AcousticOptions;

constexpr double kA = 0.1;      // equatorial semi-axis (m)
constexpr double kC = kA / 50;  // polar semi-axis: aspect 50
constexpr double kVolume = 4.0 / 3.0 * std::numbers::pi * kA * kA * kC;

// The squashed icosphere: its vertices lie on the spheroid, and the rim keeps the sphere's
// triangle count (long thin triangles there, as a CAD plate has).
test::SurfaceMesh spheroid(int level) {
  test::SurfaceMesh m = test::icosphere(kA, level);
  for (Vec3& v : m.vertices) v[2] *= kC / kA;
  return m;
}

// One rigid translation along z per frequency (unit modal amplitude: 1 m).
Soundbank translations(const test::SurfaceMesh& m, const std::vector<double>& ka, double c) {
  Soundbank bank;
  bank.vertices = m.vertices;
  bank.triangles = m.triangles;
  for (const Vec3& v : m.vertices) {
    const Vec3 g{v[0] / (kA * kA), v[1] / (kA * kA), v[2] / (kC * kC)};  // gradient of the form
    const Vec3 n = scale(g, 1.0 / norm(g));
    bank.normals.push_back({float(n[0]), float(n[1]), float(n[2])});
  }
  for (double x : ka) {
    bank.omega.push_back(x / kA * c);
    bank.decay.push_back(0.0);
    for (std::size_t i = 0; i < m.vertices.size(); ++i)
      bank.shapes.insert(bank.shapes.end(), {0.0f, 0.0f, 1.0f});
  }
  return bank;
}

// Lamb's gamma_0 = a b c * int_0^inf dl / ((c^2 + l) D(l)), D = sqrt((a^2+l)(b^2+l)(c^2+l)),
// by the substitution l = c^2 t^2 / (1 - t)^2 and Simpson's rule.
double lamb_gamma0() {
  auto f = [](double t) {
    if (t >= 1) return 0.0;
    const double l = kC * kC * t * t / ((1 - t) * (1 - t));
    const double dl = 2 * kC * kC * t / ((1 - t) * (1 - t) * (1 - t));
    return kA * kA * kC * dl / ((kC * kC + l) * (kA * kA + l) * std::sqrt(kC * kC + l));
  };
  const int n = 200000;
  double s = f(0) + f(1);
  for (int i = 1; i < n; ++i) s += (i % 2 ? 4 : 2) * f(double(i) / n);
  return s / (3.0 * n);
}

// Potential-flow far field of the body translating with velocity U along z: the dipole
// phi = -(D . grad)(e^{ikr} / 4 pi r) with D = (m'/rho + V) U, m' = gamma0 / (2 - gamma0) rho V
// (Lamb Art. 114), and p = i w rho phi, so |p| r -> rho w k D |cos t| / 4 pi.
double dipole_level(double ka, double cos_t, const AcousticOptions& o) {
  const double g = lamb_gamma0();
  const double k = ka / kA, w = k * o.sound_speed;
  const double d = kVolume * 2.0 / (2.0 - g) * w;  // U = w x 1 m
  return o.air_density * w * k * d * std::abs(cos_t) / (4 * std::numbers::pi);
}

Transfer solve_thin(const Soundbank& bank, const test::SurfaceMesh& mesh,
                    const AcousticOptions& o) {
  const precompute::RadiatingSurface surface(mesh, o);
  auto kernels = precompute::make_cpu_transfer_kernels(1);
  return precompute::compute_transfer(surface, bank, o, *kernels);
}

// rms over directions of | |p| r - want | relative to the rms of want, far away.
template <class Want>
double far_error(const Transfer& t, std::size_t mode, Want want) {
  const double r = 1e3 * kA;
  double num = 0, den = 0;
  for (int i = 0; i < 400; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / 400, rho = std::sqrt(1 - z * z), ph = 2.4 * i;
    const Vec3 x{r * rho * std::cos(ph), r * rho * std::sin(ph), r * z};
    const double got = std::abs(t.pressure(mode, x)) * r, w = want(x, z);
    num += (got - w) * (got - w), den += w * w;
  }
  return std::sqrt(num / den);
}

// Within 3 % at ka <= 0.3 (measured on this mesh: 1.5, 2.0, 2.8 % at ka 0.1, 0.2, 0.3; the
// elements' error halves per halving of their size, and the dipole itself is exact only as
// ka -> 0, by about 1 % at 0.3).
TEST(ThinRadiator, LowFrequencyAutoMatchesLambsDipole) {
  AcousticOptions o;
  const std::vector<double> ka = {0.1, 0.2, 0.3};
  const test::SurfaceMesh m = spheroid(4);
  const Transfer t = solve_thin(translations(m, ka, o.sound_speed), m, o);
  for (std::size_t i = 0; i < ka.size(); ++i) {
    const double e =
        far_error(t, i, [&](const Vec3&, double cz) { return dipole_level(ka[i], cz, o); });
    EXPECT_LT(e, 0.03) << "ka " << ka[i] << " by " << to_string(t.modes[i].method);
  }
}

// The far-field level over directions, and the complex field at 3a, within 5 % of the
// elements' (measured: level 2.5, 2.4, 1.8 %; field 2.7, 3.0, 3.0 %. Before the grid was driven
// at its own wavenumber and faces carried their reach, the field at ka 10 differed by 20 %).
TEST(ThinRadiator, WaveMatchesBoundaryElementsAtKa2To10) {
  AcousticOptions o;
  const std::vector<double> ka = {2, 5, 10};
  const test::SurfaceMesh m = spheroid(4);
  const Soundbank bank = translations(m, ka, o.sound_speed);
  o.method = AcousticOptions::Method::Bem;
  const Transfer bem = solve_thin(bank, m, o);
  o.method = AcousticOptions::Method::Wave;
  const Transfer wave = solve_thin(bank, m, o);
  for (std::size_t i = 0; i < ka.size(); ++i) {
    ASSERT_EQ(wave.modes[i].method, TransferMethod::Wave);
    const double e = far_error(
        wave, i, [&](const Vec3& x, double) { return std::abs(bem.pressure(i, x)) * norm(x); });
    double num = 0, den = 0;  // the complex field at 3a
    for (int q = 0; q < 200; ++q) {
      const double z = 1.0 - (2.0 * q + 1.0) / 200, rho = std::sqrt(1 - z * z), ph = 2.4 * q;
      const Vec3 x = scale(Vec3{rho * std::cos(ph), rho * std::sin(ph), z}, 3 * kA);
      num += std::norm(wave.pressure(i, x) - bem.pressure(i, x)),
          den += std::norm(bem.pressure(i, x));
    }
    std::printf("ka %.0f: far-field level %.4f, complex field at 3a %.4f\n", ka[i], e,
                std::sqrt(num / den));
    EXPECT_LT(e, 0.05) << "ka " << ka[i];
    EXPECT_LT(std::sqrt(num / den), 0.05) << "ka " << ka[i];
  }
}

}  // namespace
}  // namespace chladni
