// compute_transfer's time-domain path: per chord a grid, a run, a separation and each mode's
// multipoles (wave_transfer.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "../timing.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "wave_grid.hpp"
#include "wave_project.hpp"

namespace chladni::precompute {
namespace {

using wave::Problem;

// Points on the sphere of radius 2R where each expansion is checked against the box integral
// (each costs a pass over the box's faces).
constexpr std::size_t kWaveCheckPoints = 64;

// Berenger's split-field coefficients for a cell or face at depth d (m) into the layer:
// sigma = sigma_max (d / delta)^2, sigma_max = 3 c ln(1 / R0) / (2 delta), R0 = 1e-5; the
// update x' = (1 - s dt/2)/(1 + s dt/2) x - lambda / (1 + s dt/2) (difference).
void layer(double d, double delta, double c, double dt, double lambda, float& a, float& b) {
  const double sigma_max = 3.0 * c * std::log(1e5) / (2.0 * delta);
  const double s = d > 0 ? sigma_max * (d / delta) * (d / delta) : 0.0;
  a = float((1 - 0.5 * s * dt) / (1 + 0.5 * s * dt));
  b = float(lambda / (1 + 0.5 * s * dt));
}

struct Built {
  Problem problem;
  std::vector<double> omega;  ///< per mode, the frequency the grid is driven at (grid_omega)
};

// The frequency at which the grid carries a wave of the true wavenumber k = omega / c. The Yee
// scheme's dispersion, (sin(W dt/2) / (c dt))^2 = sum_a (sin(k_a h/2) / h)^2, makes its waves
// short (2 % along the axes at 8 cells a wavelength, about 1 % along diagonals): driven at
// omega, the field around the object would have the wrong wavenumber and its phase would drift
// between surface and recording box. Driven at W, with the right side averaged over
// directions, what is left is the scheme's anisotropy (+-0.8 % in k at 8 cells a wavelength).
double grid_omega(double omega, double c, double h, double dt) {
  constexpr int kDirections = 64;
  const double k = omega / c;
  double sum = 0;
  for (int i = 0; i < kDirections; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / kDirections, rho = std::sqrt(1 - z * z);
    const double ph = 2.399963 * i, n[3] = {rho * std::cos(ph), rho * std::sin(ph), z};
    for (double na : n) sum += std::pow(std::sin(0.5 * k * na * h) / h, 2);
  }
  const double s = c * dt * std::sqrt(sum / kDirections);
  return s < 1 ? 2.0 / dt * std::asin(s) : omega;  // s >= 1: beyond the grid's reach
}

// Each blocked face's share of each mode (its directions already in the object's frame, where
// the shapes are), and the modes' velocities over time. A face lying a
// reach d outside the surface carries the surface's normal velocity delayed by d / c:
//   -w sin(w (t - d/c)) = cos(w d/c) (-w sin w t) + sin(w d/c) (w cos w t),
// so each mode drives two series, in phase and in quadrature, the face's amplitudes weighting
// them by cos and sin of w d / c. q = cos(w t) is a unit modal amplitude (e^(-i w t)), ramped
// in with a raised cosine over `ramp` seconds.
void drive_faces(Problem& P, const Soundbank& bank, const Chord& chord,
                 const std::vector<std::size_t>& which, const std::vector<double>& omega,
                 const AcousticOptions& o, double dt, double ramp) {
  const std::size_t J = chord.modes.size(), S = 2 * J, nv = bank.vertices.size();
  const double c = o.sound_speed, rho_c = o.air_density * c;
  P.series = S;
  P.amplitude.assign(P.blocked.size() * S, 0.0f);
  for (std::size_t j = 0; j < J; ++j) {
    const float* shape = bank.shapes.data() + which[chord.modes[j]] * nv * 3;
    const double k = bank.damped_omega(which[chord.modes[j]]) / c;  // true, not the grid's
    for (std::size_t f = 0; f < P.blocked.size(); ++f) {
      double in_phase = 0, quadrature = 0;
      for (uint32_t e = P.blocked.start[f]; e < P.blocked.start[f + 1]; ++e) {
        const float* u = shape + 3 * std::size_t(P.blocked.vertex[e]);
        const auto& n = P.blocked.direction[e];
        const double v = P.blocked.weight[e] * (u[0] * n[0] + u[1] * n[1] + u[2] * n[2]);
        const double phase = k * P.blocked.reach[e];
        in_phase += v * std::cos(phase), quadrature += v * std::sin(phase);
      }
      P.amplitude[f * S + 2 * j] = float(rho_c * in_phase);
      P.amplitude[f * S + 2 * j + 1] = float(rho_c * quadrature);
    }
  }
  P.drive.resize(P.steps * S);
  for (std::size_t n = 0; n < P.steps; ++n) {
    const double t = (double(n) + 0.5) * dt;
    const double r = t < ramp ? 0.5 * (1 - std::cos(std::numbers::pi * t / ramp)) : 1.0;
    for (std::size_t j = 0; j < J; ++j) {
      P.drive[n * S + 2 * j] = float(-omega[j] * std::sin(omega[j] * t) * r);
      P.drive[n * S + 2 * j + 1] = float(omega[j] * std::cos(omega[j] * t) * r);
    }
  }
}

// How the object sits on a grid: x_grid = pivot + rows (x_object - pivot).
struct Orientation {
  std::array<Vec3, 3> rows;
  Vec3 pivot;
};

Built build(const RadiatingSurface& surface, const Soundbank& bank, const Chord& chord,
            const std::vector<std::size_t>& which, const WaveGridSize& size,
            const AcousticOptions& o, const Orientation& turn) {
  const WaveOptions& w = o.wave;
  Built out;
  Problem& P = out.problem;
  wave::Grid& g = P.grid;
  g.h = size.h;
  g.n = {uint32_t(size.nx), uint32_t(size.ny), uint32_t(size.nz)};
  const SurfaceMesh mesh = wave::turned(surface.mesh(), turn.rows, turn.pivot);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) P.turn[std::size_t(a)][b] = turn.rows[std::size_t(b)][a];
  P.pivot = turn.pivot;
  Vec3 lo = mesh.vertices[0], hi = lo;
  for (const Vec3& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
  // The grid is centred on the bounding box, so a body symmetric about its centre planes is
  // discretized symmetrically: a staircase that breaks a symmetry makes a spurious field where
  // the true one cancels (on the axis of a bowl's cos(n phi) modes; and faces whose reach
  // differs on a bar's two sides fill its nulls). A millionth of a cell keeps cell centres off
  // surfaces that pass exactly through them (a sphere's poles on a grid centred on it): such a
  // centre is inside along one axis and outside along another, and its pressure leaks.
  constexpr double kOffGrid[3] = {0.71e-6, 0.53e-6, 0.37e-6};
  for (int a = 0; a < 3; ++a)
    g.origin[a] = 0.5 * (lo[a] + hi[a]) - (0.5 * double(g.n[a]) - kOffGrid[a]) * g.h;
  const double c = o.sound_speed, dt = size.dt, lambda = c * dt / g.h;
  const double delta = w.pml_cells * g.h;
  for (int a = 0; a < 3; ++a) {
    const uint32_t n = g.n[a];
    P.pml_lo[a] = uint32_t(w.pml_cells), P.pml_hi[a] = n - uint32_t(w.pml_cells);
    for (auto* v : {&P.pa[a], &P.pb[a], &P.wa[a], &P.wb[a]}) v->resize(n);
    for (uint32_t i = 0; i < n; ++i) {
      auto depth = [&](double x) {  // x in cells from the domain's lower edge
        return std::max({0.0, (w.pml_cells - x) * g.h, (x - (n - w.pml_cells)) * g.h});
      };
      layer(depth(i + 0.5), delta, c, dt, lambda, P.pa[a][i], P.pb[a][i]);
      layer(depth(i + 1.0), delta, c, dt, lambda, P.wa[a][i], P.wb[a][i]);
    }
  }
  P.blocked = wave::block_faces(mesh, g);
  for (auto& d : P.blocked.direction) {  // into the object's frame, once for every mode
    const Vec3 n = wave::turn_vector(P.turn, {d[0], d[1], d[2]});
    d = {float(n[0]), float(n[1]), float(n[2])};
  }
  for (std::size_t j : chord.modes)
    out.omega.push_back(grid_omega(bank.damped_omega(which[j]), c, g.h, dt));
  P.steps = size.steps;
  P.first_sample = size.settle_steps;
  P.stride = size.stride;
  drive_faces(P, bank, chord, which, out.omega, o, dt, w.ramp_periods / chord.f_min);
  const uint32_t box = uint32_t(w.pml_cells + 2);
  P.record = wave::record_box(g, {box, box, box}, {g.n[0] - box, g.n[1] - box, g.n[2] - box});
  return out;
}

std::string chord_note(std::size_t index, std::size_t count, const Chord& chord,
                       const WaveGridSize& s) {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "chord %zu/%zu: %zu modes %.0f-%.0f Hz, grid %zux%zux%zu (h %.2f mm), %zu steps",
                index + 1, count, chord.modes.size(), chord.f_min, chord.f_max, s.nx, s.ny, s.nz,
                s.h * 1e3, s.steps);
  return buf;
}

// One run of the time-domain path: the surface, the bank, the modes it solves and where the
// results go.
struct WaveRun {
  const RadiatingSurface& surface;
  const Soundbank& bank;
  const AcousticOptions& o;
  WaveLayout layout;
  std::vector<ModeTransfer>& modes;
  std::vector<std::vector<std::complex<double>>>& coeffs;
  TransferTimes* times;
  wave::Stepper& stepper;
};

// Refuses a chord over the memory or work limit before anything is allocated.
void check_budget(const WaveOptions& w, const WaveGridSize& size, const std::string& label) {
  if (w.max_memory > 0 && size.bytes > w.max_memory) {
    throw BudgetError("transfer: the time-domain grid of " + label + " needs about " +
                      std::to_string(int(size.bytes / 1e6)) + " MB, over the memory limit");
  }
  if (size.cell_steps() > w.max_cell_steps) {
    char work[160];
    std::snprintf(work, sizeof work,
                  " would take %.3g cell-steps, over the limit of %.3g (an object this size at "
                  "these frequencies)",
                  size.cell_steps(), w.max_cell_steps);
    throw BudgetError("transfer: the time-domain " + label + work);
  }
}

// One orientation's run of a chord: its problem, separation and multipoles.
struct TurnRun {
  Built built;
  wave::Separated sep;
  std::vector<std::vector<cd>> c;  ///< regular-wave coefficients per mode
};

TurnRun run_turn(WaveRun& r, const Chord& chord, const std::vector<std::size_t>& which,
                 const WaveGridSize& size, const Orientation& turn, const std::vector<double>& ks,
                 const std::vector<int>& Ls) {
  auto t0 = std::chrono::steady_clock::now();
  TurnRun out{build(r.surface, r.bank, chord, which, size, r.o, turn), {}, {}};
  if (r.times) r.times->matrix += seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  std::vector<float> samples;
  r.stepper.run(out.built.problem, samples, {});
  if (r.times) r.times->solve += seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  out.sep = wave::separate(out.built.problem, samples, out.built.omega, size.dt);
  out.c = wave::box_multipoles(out.built.problem, out.sep, ks, r.surface.centre(), Ls,
                               r.o.wave.threads);
  if (r.times) r.times->expand += seconds_since(t0);
  return out;
}

// Steps one chord in every orientation and stores each of its modes (which[chord.modes[j]] in
// the bank): the mean of the orientations' expansions, whose staircase errors differ (turned by
// 90 / turns degrees about the axis of near symmetry, a field's coupling through the grid's
// four-fold symmetry, cos n phi to n +- 4, changes sign and cancels in the mean). On a retry
// only where the new separation is better than the stored one.
void solve_chord(WaveRun& r, const Chord& chord, const std::vector<std::size_t>& which,
                 const WaveGridSize& size, uint16_t number, bool retry) {
  const AcousticOptions& o = r.o;
  const RadiatingSurface& surface = r.surface;
  std::vector<double> ks;
  std::vector<int> Ls;
  for (std::size_t j = 0; j < chord.modes.size(); ++j) {
    ks.push_back(r.bank.damped_omega(which[chord.modes[j]]) / o.sound_speed);
    Ls.push_back(expansion_order(ks.back(), surface.radius(), o));
  }
  std::vector<TurnRun> runs;
  for (const auto& rows : r.layout.turns)
    runs.push_back(run_turn(r, chord, which, size, {rows, r.layout.pivot}, ks, Ls));
  const auto t0 = std::chrono::steady_clock::now();
  const double share = 1.0 / double(runs.size());
  for (std::size_t j = 0; j < chord.modes.size(); ++j) {
    const std::size_t i = which[chord.modes[j]];
    double error = 0, residual = 0;
    for (const TurnRun& t : runs)
      error = std::max(error, t.sep.error[j]), residual = std::max(residual, t.sep.residual);
    if (retry && !(error < r.modes[i].held_out_error)) continue;
    const double k = ks[j];
    const int L = Ls[j];
    std::vector<cd> c(runs[0].c[j].size(), cd(0.0));
    for (const TurnRun& t : runs)
      for (std::size_t q = 0; q < c.size(); ++q) c[q] += share * t.c[j][q];
    std::vector<cd> h(std::size_t(L) + 1);
    sph_hankel1(L, k * surface.radius(), h.data());
    for (int l = 0; l <= L; ++l)
      for (int m = -l; m <= l; ++m) c[sh_index(l, m)] *= h[std::size_t(l)];
    ModeTransfer mt = finish_expansion(
        surface, k, L, c, o,
        [&](const std::vector<Vec3>& pts, cd* out) {
          std::vector<Vec3> abs(pts.size());
          for (std::size_t q = 0; q < pts.size(); ++q) abs[q] = add(pts[q], surface.centre());
          std::vector<cd> one(pts.size());
          std::fill(out, out + pts.size(), cd(0.0));
          for (const TurnRun& t : runs) {
            wave::box_field(t.built.problem, t.sep, j, k, abs, one.data(), o.wave.threads);
            for (std::size_t q = 0; q < pts.size(); ++q) out[q] += share * one[q];
          }
        },
        kWaveCheckPoints);
    mt.method = TransferMethod::Wave;
    mt.sources = uint32_t(std::min<std::size_t>(size.cells(), UINT32_MAX));
    mt.fit_residual = float(residual);
    mt.held_out_error = float(error);
    mt.iterations = number;
    r.modes[i] = mt;
    r.coeffs[i] = std::move(c);
  }
  if (r.times) r.times->expand += seconds_since(t0);
}

uint16_t chord_number(std::size_t index) {
  return uint16_t(std::min<std::size_t>(index + 1, UINT16_MAX));
}

}  // namespace

void compute_transfer_wave(const RadiatingSurface& surface, const Soundbank& bank,
                           const std::vector<std::size_t>& which, const AcousticOptions& o,
                           std::vector<ModeTransfer>& modes,
                           std::vector<std::vector<std::complex<double>>>& coeffs,
                           TransferTimes* times, const std::function<void()>& done,
                           const std::function<void(const std::string&)>& note) {
  if (which.empty()) return;
  std::unique_ptr<wave::Stepper> stepper = wave::make_stepper(o.wave);
  WaveRun r{surface, bank, o, wave_layout(surface.mesh(), o.wave), modes, coeffs, times, *stepper};
  if (note && r.layout.turns.size() > 1) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "%zu orientations about the %c axis (cos 4 phi content of the surface %.3f)",
                  r.layout.turns.size(), "xyz"[r.layout.axis], r.layout.fourfold);
    note(buf);
  }
  // Settling beyond the ramp: about twice the padded object's diagonal, crossed at c.
  double span = 0;
  for (int a = 0; a < 3; ++a)
    span += (r.layout.hi[a] - r.layout.lo[a]) * (r.layout.hi[a] - r.layout.lo[a]);
  const double settle = 3.0 * std::sqrt(span) / o.sound_speed;
  auto hz_of = [&](const std::vector<std::size_t>& list) {
    std::vector<double> hz;
    for (std::size_t i : list) hz.push_back(bank.damped_omega(i) / (2 * std::numbers::pi));
    return hz;
  };
  const std::vector<Chord> chords = plan_chords(hz_of(which), settle, o.wave);
  std::vector<std::size_t> weak;
  for (std::size_t ci = 0; ci < chords.size(); ++ci) {
    const Chord& chord = chords[ci];
    const WaveGridSize size =
        wave_grid_size(r.layout, chord, o.sound_speed, surface.area(), o.wave);
    const std::string label = chord_note(ci, chords.size(), chord, size);
    check_budget(o.wave, size, label);
    if (note) note(label);
    solve_chord(r, chord, which, size, chord_number(ci), false);
    for (std::size_t m : chord.modes) {
      if (done) done();
      if (o.wave.retry_separation > 0 && chord.modes.size() > 1 &&
          !(modes[which[m]].held_out_error <= o.wave.retry_separation))
        weak.push_back(which[m]);
    }
  }
  if (weak.empty()) return;
  std::sort(weak.begin(), weak.end());
  const std::vector<Chord> again = plan_chords(hz_of(weak), settle, o.wave);
  for (std::size_t ci = 0; ci < again.size(); ++ci) {
    const Chord& chord = again[ci];
    const WaveGridSize size =
        wave_grid_size(r.layout, chord, o.sound_speed, surface.area(), o.wave);
    const std::string label = "weak modes again, " + chord_note(ci, again.size(), chord, size);
    check_budget(o.wave, size, label);
    if (note) note(label);
    solve_chord(r, chord, weak, size, chord_number(chords.size() + ci), true);
  }
}

}  // namespace chladni::precompute
