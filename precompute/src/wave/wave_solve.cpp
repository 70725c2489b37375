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
  std::vector<double> omega;
};

Built build(const RadiatingSurface& surface, const Soundbank& bank, const Chord& chord,
            const std::vector<std::size_t>& which, const WaveGridSize& size,
            const AcousticOptions& o) {
  const WaveOptions& w = o.wave;
  Built out;
  Problem& P = out.problem;
  wave::Grid& g = P.grid;
  g.h = size.h;
  g.n = {uint32_t(size.nx), uint32_t(size.ny), uint32_t(size.nz)};
  const SurfaceMesh& mesh = surface.mesh();
  Vec3 lo = mesh.vertices[0], hi = lo;
  for (const Vec3& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
  // The grid is centred on the bounding box, so a body symmetric about its centre planes is
  // discretized symmetrically (a staircase that breaks a symmetry makes a spurious field where
  // the true one cancels, e.g. on the axis of a bowl's cos(n phi) modes). A small fraction of
  // a cell keeps grid lines off the vertices of axis-aligned meshes.
  const double jitter[3] = {0.0, 0.0, 0.0345678912};
  for (int a = 0; a < 3; ++a)
    g.origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * double(g.n[a]) * g.h + jitter[a] * g.h;
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
  const std::size_t J = chord.modes.size(), nv = mesh.vertices.size();
  P.modes = J;
  P.amplitude.assign(P.blocked.size() * J, 0.0f);
  const double rho_c = o.air_density * c;
  for (std::size_t j = 0; j < J; ++j) {
    const std::size_t mode = which[chord.modes[j]];
    out.omega.push_back(bank.damped_omega(mode));
    const float* shape = bank.shapes.data() + mode * nv * 3;
    for (std::size_t f = 0; f < P.blocked.size(); ++f) {
      double v = 0;
      for (uint32_t e = P.blocked.start[f]; e < P.blocked.start[f + 1]; ++e) {
        const float* u = shape + 3 * std::size_t(P.blocked.vertex[e]);
        const auto& d = P.blocked.direction[e];
        v += P.blocked.weight[e] * (u[0] * d[0] + u[1] * d[1] + u[2] * d[2]);
      }
      P.amplitude[f * J + j] = float(rho_c * v);
    }
  }
  // Modal velocity of q = cos(w t) (unit amplitude, e^(-i w t)): -w sin(w t), ramped in.
  P.steps = size.steps;
  P.first_sample = size.settle_steps;
  P.stride = size.stride;
  P.drive.resize(P.steps * J);
  const double ramp = w.ramp_periods / chord.f_min;
  for (std::size_t n = 0; n < P.steps; ++n) {
    const double t = (double(n) + 0.5) * dt;
    const double r = t < ramp ? 0.5 * (1 - std::cos(std::numbers::pi * t / ramp)) : 1.0;
    for (std::size_t j = 0; j < J; ++j)
      P.drive[n * J + j] = float(-out.omega[j] * std::sin(out.omega[j] * t) * r);
  }
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
  double lo[3], hi[3];
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

// Steps one chord and stores each of its modes (which[chord.modes[j]] in the bank); on a retry
// only where the new separation is better than the stored one.
void solve_chord(WaveRun& r, const Chord& chord, const std::vector<std::size_t>& which,
                 const WaveGridSize& size, uint16_t number, bool retry) {
  const AcousticOptions& o = r.o;
  const RadiatingSurface& surface = r.surface;
  auto t0 = std::chrono::steady_clock::now();
  const Built built = build(surface, r.bank, chord, which, size, o);
  if (r.times) r.times->matrix += seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  std::vector<float> samples;
  r.stepper.run(built.problem, samples, {});
  if (r.times) r.times->solve += seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  const wave::Separated sep = wave::separate(built.problem, samples, built.omega, size.dt);
  std::vector<double> ks;
  std::vector<int> Ls;
  for (double w : built.omega) {
    ks.push_back(w / o.sound_speed);
    Ls.push_back(expansion_order(ks.back(), surface.radius(), o));
  }
  std::vector<std::vector<cd>> cs =
      wave::box_multipoles(built.problem, sep, ks, surface.centre(), Ls, o.wave.threads);
  for (std::size_t j = 0; j < chord.modes.size(); ++j) {
    const std::size_t i = which[chord.modes[j]];
    if (retry && !(sep.error[j] < r.modes[i].held_out_error)) continue;
    const double k = ks[j];
    const int L = Ls[j];
    std::vector<cd>& c = cs[j];
    std::vector<cd> h(std::size_t(L) + 1);
    sph_hankel1(L, k * surface.radius(), h.data());
    for (int l = 0; l <= L; ++l)
      for (int m = -l; m <= l; ++m) c[sh_index(l, m)] *= h[std::size_t(l)];
    ModeTransfer mt = finish_expansion(
        surface, k, L, c, o,
        [&](const std::vector<Vec3>& pts, cd* out) {
          std::vector<Vec3> abs(pts.size());
          for (std::size_t q = 0; q < pts.size(); ++q) abs[q] = add(pts[q], surface.centre());
          wave::box_field(built.problem, sep, j, k, abs, out, o.wave.threads);
        },
        kWaveCheckPoints);
    mt.method = TransferMethod::Wave;
    mt.sources = uint32_t(std::min<std::size_t>(size.cells(), UINT32_MAX));
    mt.fit_residual = float(sep.residual);
    mt.held_out_error = float(sep.error[j]);
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
  WaveRun r{surface, bank, o, {}, {}, modes, coeffs, times, *stepper};
  const SurfaceMesh& mesh = surface.mesh();
  for (int a = 0; a < 3; ++a) r.lo[a] = r.hi[a] = mesh.vertices[0][a];
  for (const Vec3& v : mesh.vertices)
    for (int a = 0; a < 3; ++a)
      r.lo[a] = std::min(r.lo[a], v[a]), r.hi[a] = std::max(r.hi[a], v[a]);
  // Settling beyond the ramp: about twice the padded object's diagonal, crossed at c.
  double span = 0;
  for (int a = 0; a < 3; ++a) span += (r.hi[a] - r.lo[a]) * (r.hi[a] - r.lo[a]);
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
        wave_grid_size(r.lo, r.hi, chord, o.sound_speed, surface.area(), o.wave);
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
        wave_grid_size(r.lo, r.hi, chord, o.sound_speed, surface.area(), o.wave);
    const std::string label = "weak modes again, " + chord_note(ci, again.size(), chord, size);
    check_budget(o.wave, size, label);
    if (note) note(label);
    solve_chord(r, chord, weak, size, chord_number(chords.size() + ci), true);
  }
}

}  // namespace chladni::precompute
