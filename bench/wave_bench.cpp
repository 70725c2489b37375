// The time-domain transfer solve (docs/transfer.md, docs/PERFORMANCE.md "Time-domain transfer").
//   chladni_wave_bench sphere [--l L,L..] [--ka KA,KA..] [--radius M] [--level N] [common]
//     a sphere's surface moving as P_l(cos t) against the exact field (rms over directions at 3a);
//   chladni_wave_bench bank BANK --reference REF [--method wave|auto|bem|stored] [--modes N]
//   [common]
//     BANK's modes solved again, compared with REF's transfer (the same modes, e.g. solved by
//     --transfer-method bem): far-field level per cluster of modes within 0.3 % in frequency
//     (summed power), rms and worst dB over 400 directions.
//   common: [--cpw X] [--min-cells N] [--turns N] [--backend cpu|gpu] [--json OUT]
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "../tests/fem_fixtures.hpp"
#include "bench_support.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"

using namespace chladni;
using cd = std::complex<double>;
using precompute::AcousticOptions;

namespace {

struct Args {
  std::string what, bank, reference, json, backend = "cpu", method = "wave";
  std::vector<int> l{0, 1, 2, 4, 6, 8, 10};
  std::vector<double> ka{2, 5, 10, 20, 30};
  double radius = 0.1, cpw = 0, wall = 0;
  int level = 5, min_cells = 0, m = 0, turns = 0;
  std::size_t modes = 100000;
};

template <class T>
std::vector<T> list(const std::string& s) {
  std::vector<T> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) out.push_back(T(std::stod(item)));
  return out;
}

Args parse(int argc, char** argv) {
  if (argc < 2) throw std::invalid_argument("usage: chladni_wave_bench sphere|bank ...");
  Args a;
  a.what = argv[1];
  int i = 2;
  if (a.what == "bank") {
    if (argc < 3) throw std::invalid_argument("bank: need BANK");
    a.bank = argv[i++];
  } else if (a.what != "sphere") {
    throw std::invalid_argument("first argument: sphere or bank");
  }
  for (; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--l")
      a.l = list<int>(v);
    else if (k == "--ka")
      a.ka = list<double>(v);
    else if (k == "--radius")
      a.radius = std::stod(v);
    else if (k == "--level")
      a.level = std::stoi(v);
    else if (k == "--m")
      a.m = std::stoi(v);
    else if (k == "--wall")
      a.wall = std::stod(v);
    else if (k == "--cpw")
      a.cpw = std::stod(v);
    else if (k == "--min-cells")
      a.min_cells = std::stoi(v);
    else if (k == "--turns")
      a.turns = std::stoi(v);
    else if (k == "--backend")
      a.backend = v;
    else if (k == "--method")
      a.method = v;
    else if (k == "--reference")
      a.reference = v;
    else if (k == "--modes")
      a.modes = std::stoul(v);
    else if (k == "--json")
      a.json = v;
    else
      throw std::invalid_argument("unknown option " + k);
  }
  if (a.what == "bank" && a.reference.empty())
    throw std::invalid_argument("bank: need --reference");
  return a;
}

AcousticOptions options(const Args& a) {
  AcousticOptions o;
  using M = AcousticOptions::Method;
  o.method = a.method == "auto" ? M::Auto : a.method == "bem" ? M::Bem : M::Wave;
  if (a.cpw > 0) o.wave.cells_per_wavelength = a.cpw;
  if (a.min_cells > 0) o.wave.min_cells = a.min_cells;
  if (a.turns > 0) o.wave.grid_turns = a.turns;
  if (a.backend == "gpu") o.wave.gpu = std::make_shared<gpu::Context>();
  return o;
}

Transfer solve(const Soundbank& bank, const precompute::SurfaceMesh& mesh, const AcousticOptions& o,
               double& seconds) {
  const precompute::RadiatingSurface surface(mesh, o);
  auto kernels = precompute::make_cpu_transfer_kernels(1);
  const auto t0 = bench::clock_type::now();
  precompute::TransferTimes times;
  Transfer t = precompute::compute_transfer(
      surface, bank, o, *kernels, &times, {},
      [](const std::string& s) { std::fprintf(stderr, "  %s\n", s.c_str()); });
  seconds = bench::seconds_since(t0);
  std::fprintf(stderr, "  grids %.2f s, stepping %.2f s, separation and multipoles %.2f s\n",
               times.matrix, times.solve, times.expand);
  return t;
}

std::vector<Vec3> directions(int n) {
  std::vector<Vec3> d;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n, rho = std::sqrt(1 - z * z), ph = 2.39996 * i;
    d.push_back({rho * std::cos(ph), rho * std::sin(ph), z});
  }
  return d;
}

// The real spherical harmonic Y_l,min(m,l) (0 where m > l is asked of a lower l: Y_l0).
double harmonic(int l, int m, const Vec3& d) {
  std::vector<double> y(sh_count(l));
  real_sh(l, d, y.data());
  return y[sh_index(l, std::min(m, l))];
}

int run_sphere(const Args& a) {
  const AcousticOptions o = options(a);
  // --wall: a shell of that thickness moving rigidly through it (its outside sees the same
  // velocity as the solid ball's surface; the closed cavity inside does not radiate).
  const test::SurfaceMesh s = a.wall > 0 ? test::hollow_sphere(a.radius, a.wall, a.level)
                                         : test::icosphere(a.radius, a.level);
  Soundbank bank;
  bank.vertices = s.vertices, bank.triangles = s.triangles;
  std::vector<std::pair<int, double>> cases;
  for (double ka : a.ka)
    for (int l : a.l) cases.push_back({l, ka});
  for (auto [l, ka] : cases) {
    bank.omega.push_back(ka / a.radius * o.sound_speed), bank.decay.push_back(0.0);
    for (const Vec3& v : s.vertices) {
      const Vec3 n = scale(v, 1.0 / norm(v)), d = scale(n, harmonic(l, a.m, n));
      for (int q = 0; q < 3; ++q) bank.shapes.push_back(float(d[q]));
    }
  }
  for (const Vec3& v : s.vertices) {
    const Vec3 n = scale(v, 1.0 / norm(v));
    bank.normals.push_back({float(n[0]), float(n[1]), float(n[2])});
  }
  double seconds = 0;
  const Transfer t = solve(bank, s, o, seconds);
  nlohmann::json rows = nlohmann::json::array();
  const double r = 3 * a.radius;
  std::printf("%4s %6s %9s %9s\n", "l", "ka", "error", "worst dB");
  for (std::size_t m = 0; m < cases.size(); ++m) {
    const auto [l, ka] = cases[m];
    const double k = ka / a.radius;
    std::vector<cd> h(std::size_t(l) + 1);
    sph_hankel1(l, k * r, h.data());
    const cd scale_exact = cd(0, o.air_density * o.sound_speed) * cd(0.0, -k * o.sound_speed) *
                           h[std::size_t(l)] / sph_hankel1_derivative(l, k * a.radius);
    double num = 0, den = 0, worst = 0, peak = 0;
    const auto dirs = directions(400);
    for (const Vec3& d : dirs) peak = std::max(peak, std::abs(harmonic(l, a.m, d)));
    for (const Vec3& d : dirs) {
      const double pl = harmonic(l, a.m, d);
      const cd want = scale_exact * pl, got = t.pressure(m, scale(d, r));
      num += std::norm(got - want), den += std::norm(want);
      if (std::abs(pl) > 0.3 * peak)
        worst = std::max(worst, std::abs(20 * std::log10(std::abs(got) / std::abs(want))));
    }
    const double e = std::sqrt(num / den);
    std::printf("%4d %6.1f %9.4f %9.2f\n", l, ka, e, worst);
    rows.push_back({{"l", l}, {"ka", ka}, {"error", e}, {"worst_db", worst}});
  }
  std::printf("%zu modes in %.1f s (%s)\n", cases.size(), seconds, a.backend.c_str());
  if (!a.json.empty())
    std::ofstream(a.json) << nlohmann::json{{"sphere", rows}, {"seconds", seconds}}.dump(1);
  return 0;
}

}  // namespace

int run_bank(const Args& a);

int main(int argc, char** argv) {
  const Args a = bench::parse_or_exit(parse, argc, argv);
  try {
    return a.what == "sphere" ? run_sphere(a) : run_bank(a);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "chladni_wave_bench: %s\n", e.what());
    return 1;
  }
}

namespace {

// Clusters of modes within 0.3 % in frequency (ascending modes): degenerate partners, whose
// split of the field between them is arbitrary, compare by their summed power.
std::vector<std::vector<std::size_t>> clusters(const Soundbank& b, std::size_t count) {
  std::vector<std::vector<std::size_t>> out;
  for (std::size_t i = 0; i < count; ++i) {
    if (out.empty() || b.damped_omega(i) > 1.003 * b.damped_omega(out.back().front()))
      out.push_back({});
    out.back().push_back(i);
  }
  return out;
}

// Far-field level (dB re 1 Pa at 1 m per unit modal amplitude) of each cluster in 400
// directions: 20 log10(r |p|) at r = 50 R, summed over the cluster's modes in power.
nlohmann::json far_field(const Soundbank& b, const Transfer& t, std::size_t count) {
  const auto dirs = directions(400);
  const double r = 50 * t.radius;
  nlohmann::json out = nlohmann::json::array();
  for (const auto& c : clusters(b, count)) {
    std::vector<double> db;
    for (const Vec3& d : dirs) {
      double power = 0;
      for (std::size_t m : c) power += std::norm(r * t.pressure(m, add(t.centre, scale(d, r))));
      db.push_back(std::round(100 * 10 * std::log10(std::max(power, 1e-30))) / 100);
    }
    std::vector<double> hz;
    for (std::size_t m : c) hz.push_back(b.damped_omega(m) / (2 * std::numbers::pi));
    out.push_back({{"hz", hz}, {"db", db}});
  }
  return out;
}

// One cluster's levels against the reference's, in dB over the same directions.
struct Difference {
  double rms = 0, worst = 0;
  std::size_t worst_direction = 0;
  double power = 0;     ///< radiated power (mean over directions), got over want
  double lobe_rms = 0;  ///< rms over the directions within 10 dB of the reference's loudest
};

Difference difference(const nlohmann::json& got, const nlohmann::json& want) {
  Difference d;
  double sum = 0, lobe = 0, pg = 0, pw = 0, peak = -1e300;
  std::size_t lobe_n = 0;
  for (const auto& w : want) peak = std::max(peak, w.get<double>());
  for (std::size_t i = 0; i < got.size(); ++i) {
    const double g = got[i].get<double>(), w = want[i].get<double>(), e = g - w;
    sum += e * e;
    if (std::abs(e) > d.worst) d.worst = std::abs(e), d.worst_direction = i;
    if (w >= peak - 10) lobe += e * e, ++lobe_n;
    pg += std::pow(10.0, g / 10), pw += std::pow(10.0, w / 10);
  }
  d.rms = std::sqrt(sum / double(got.size()));
  d.lobe_rms = std::sqrt(lobe / double(std::max<std::size_t>(lobe_n, 1)));
  d.power = 10 * std::log10(pg / pw);
  return d;
}

}  // namespace

// BANK's transfer (solved again with --resolve-options, else as stored) against a reference's
// far field: per cluster the rms and worst dB difference over directions.
int run_bank(const Args& a) {
  Soundbank b = read_soundbank(a.bank);
  const std::size_t count = std::min(a.modes, b.mode_count());
  double seconds = 0;
  if (a.reference.empty()) throw std::invalid_argument("need --reference");
  if (a.method != "stored") {
    precompute::SurfaceMesh mesh{b.vertices, b.triangles};
    Soundbank head = b;
    head.omega.resize(count), head.decay.resize(count);
    head.shapes.resize(count * b.vertices.size() * 3);
    head.residual.resize(std::min(head.residual.size(), count));
    b.transfer = solve(head, mesh, options(a), seconds);
    float worst = 0;
    for (const ModeTransfer& m : b.transfer->modes) worst = std::max(worst, m.held_out_error);
    std::printf("solved %zu modes (%s): largest held-out error %.3g\n", count, a.method.c_str(),
                double(worst));
  }
  if (!b.transfer) throw std::invalid_argument(a.bank + " has no transfer");
  const nlohmann::json got = far_field(b, *b.transfer, count);
  if (a.reference.size() > 5 && a.reference.substr(a.reference.size() - 5) == ".json" &&
      !std::ifstream(a.reference)) {
    std::ofstream(a.reference) << nlohmann::json{{"clusters", got}}.dump();
    std::printf("wrote %s (%zu clusters)\n", a.reference.c_str(), got.size());
    return 0;
  }
  const nlohmann::json want = nlohmann::json::parse(std::ifstream(a.reference))["clusters"];
  if (want.size() < got.size()) throw std::invalid_argument("the reference has fewer clusters");
  std::size_t within = 0, all = 0, power_within = 0, lobe_within = 0;
  double worst_rms = 0, worst_any = 0;
  nlohmann::json rows = nlohmann::json::array();
  std::printf("%9s %5s %8s %8s %6s %8s %8s %8s\n", "Hz", "modes", "rms dB", "max dB", "dir",
              "power dB", "lobe dB", "method");
  for (std::size_t c = 0; c < got.size(); ++c) {
    const Difference e = difference(got[c]["db"], want[c]["db"]);
    const double hz = got[c]["hz"][0].get<double>();
    std::size_t first = 0;
    for (std::size_t q = 0; q < c; ++q) first += got[q]["hz"].size();
    const char* method = to_string(b.transfer->modes[first].method);
    std::printf("%9.1f %5zu %8.2f %8.2f %6zu %8.2f %8.2f %8s\n", hz, got[c]["hz"].size(), e.rms,
                e.worst, e.worst_direction, e.power, e.lobe_rms, method);
    within += e.rms <= 1.5, ++all;
    power_within += std::abs(e.power) <= 1.0, lobe_within += e.lobe_rms <= 1.5;
    worst_rms = std::max(worst_rms, e.rms), worst_any = std::max(worst_any, e.worst);
    rows.push_back({{"hz", hz},
                    {"rms_db", e.rms},
                    {"max_db", e.worst},
                    {"worst_direction", e.worst_direction},
                    {"power_db", e.power},
                    {"lobe_rms_db", e.lobe_rms},
                    {"method", method}});
  }
  std::printf(
      "radiated power within 1 dB: %zu of %zu; within 1.5 dB rms over the directions "
      "within 10 dB of the reference's loudest: %zu of %zu\n",
      power_within, all, lobe_within, all);
  std::printf(
      "%zu of %zu clusters within 1.5 dB rms (%.1f %%); worst rms %.2f dB, worst "
      "direction %.2f dB; solve %.1f s\n",
      within, all, 100.0 * double(within) / double(all), worst_rms, worst_any, seconds);
  if (!a.json.empty())
    std::ofstream(a.json) << nlohmann::json{{"clusters", rows}, {"seconds", seconds}}.dump(1);
  return 0;
}
