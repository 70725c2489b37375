// Boundary-element convergence on a soundbank (docs/transfer.md, "BEM accuracy"): each of the
// first N modes solved on the elements the wavelength asks for and again with every element
// halved; the far-field level at 1 m in 64 directions, compared where the finer field is within
// 20 dB of its loudest direction (off the nulls, where a level is meaningless).
// Usage: chladni_bem_convergence BANK [--modes N] [--json OUT]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "chladni/core/soundbank.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/precompute/memory_budget.hpp"

using namespace chladni;
using cd = std::complex<double>;

static Transfer solve(const precompute::RadiatingSurface& surface, const Soundbank& bank,
                      precompute::AcousticOptions o, int extra, double& seconds,
                      std::vector<std::size_t>& elements) {
  o.bem_extra_levels = extra;
  const std::size_t n = bank.mode_count();
  std::vector<ModeTransfer> modes(n);
  std::vector<std::vector<cd>> coeffs(n);
  std::vector<std::size_t> which(n);
  for (std::size_t i = 0; i < n; ++i) which[i] = i;
  const auto t0 = std::chrono::steady_clock::now();
  precompute::compute_transfer_bem(surface, bank, which, o, modes, coeffs, nullptr, [] {});
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Transfer t;
  t.centre = surface.centre();
  t.radius = surface.radius();
  elements.clear();
  for (std::size_t i = 0; i < n; ++i) {
    t.add_mode(modes[i], coeffs[i]);
    elements.push_back(modes[i].sources);
  }
  return t;
}

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s BANK [--modes N] [--json OUT]\n", argv[0]);
    return 2;
  }
  std::string json_path;
  std::size_t count = 20;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--modes")) count = std::stoul(argv[i + 1]);
    if (!std::strcmp(argv[i], "--json")) json_path = argv[i + 1];
  }
  Soundbank bank = read_soundbank(argv[1]);
  count = std::min(count, bank.mode_count());
  bank.omega.resize(count), bank.decay.resize(count), bank.residual.resize(count);
  bank.shapes.resize(count * bank.vertices.size() * 3);
  bank.transfer.reset();
  precompute::AcousticOptions o;
  o.method = precompute::AcousticOptions::Method::Bem;
  o.bem_max_memory = precompute::default_memory_budget();
  const precompute::RadiatingSurface surface({bank.vertices, bank.triangles}, o);
  double s0 = 0, s1 = 0;
  std::vector<std::size_t> n0, n1;
  const Transfer coarse = solve(surface, bank, o, 0, s0, n0);
  const Transfer fine = solve(surface, bank, o, 1, s1, n1);
  // 64 directions on a Fibonacci sphere, 1 m from the expansion centre.
  std::vector<Vec3> points;
  for (int d = 0; d < 64; ++d) {
    const double z = 1 - (d + 0.5) / 32.0, r = std::sqrt(1 - z * z);
    const double phi = d * std::numbers::pi * (3 - std::sqrt(5.0));
    points.push_back(add(coarse.centre, {r * std::cos(phi), r * std::sin(phi), z}));
  }
  std::printf("%s: first %zu modes; %.0f s on the wavelength's elements, %.0f s halved\n", argv[1],
              count, s0, s1);
  std::printf("%5s %10s %9s %9s %11s %11s %7s\n", "mode", "f (Hz)", "elements", "halved",
              "max dB diff", "rms dB diff", "dirs");
  nlohmann::json out = nlohmann::json::array();
  double worst = 0;
  for (std::size_t i = 0; i < count; ++i) {
    std::vector<double> a(points.size()), b(points.size());
    double loudest = 0;
    for (std::size_t d = 0; d < points.size(); ++d) {
      a[d] = std::abs(coarse.pressure(i, points[d]));
      b[d] = std::abs(fine.pressure(i, points[d]));
      loudest = std::max(loudest, b[d]);
    }
    double max_db = 0, sum = 0;
    int used = 0;
    for (std::size_t d = 0; d < points.size(); ++d) {
      if (!(b[d] >= 0.1 * loudest) || !(a[d] > 0)) continue;
      const double db = 20 * std::log10(a[d] / b[d]);
      max_db = std::max(max_db, std::abs(db));
      sum += db * db;
      ++used;
    }
    const double rms = used ? std::sqrt(sum / used) : 0.0;
    worst = std::max(worst, max_db);
    const double hz = bank.damped_omega(i) / (2 * std::numbers::pi);
    std::printf("%5zu %10.1f %9zu %9zu %11.3f %11.3f %7d\n", i, hz, n0[i], n1[i], max_db, rms,
                used);
    out.push_back({{"mode", i},
                   {"frequency_hz", hz},
                   {"elements", n0[i]},
                   {"elements_halved", n1[i]},
                   {"max_db_difference", max_db},
                   {"rms_db_difference", rms},
                   {"directions", used}});
  }
  std::printf("worst: %.3f dB\n", worst);
  if (!json_path.empty()) std::ofstream(json_path) << out.dump(2) << '\n';
  return 0;
}
