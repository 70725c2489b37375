// Chords and grids of the time-domain transfer solve (wave_transfer.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "chladni/core/error.hpp"
#include "chladni/precompute/wave_transfer.hpp"

namespace chladni::precompute {
namespace {

// First-fit packing of ascending frequencies into chords whose members are >= gap apart.
std::vector<Chord> pack(std::span<const double> hz, const std::vector<std::size_t>& band,
                        double gap, std::size_t max_chord) {
  std::vector<Chord> chords;
  for (std::size_t m : band) {
    Chord* home = nullptr;
    for (Chord& c : chords) {
      if (c.modes.size() < max_chord && hz[m] - c.f_max >= gap) {
        home = &c;
        break;
      }
    }
    if (!home) {
      chords.push_back({{}, hz[m], hz[m], 0.0});
      home = &chords.back();
    } else {
      const double g = hz[m] - home->f_max;
      home->min_gap = home->min_gap > 0 ? std::min(home->min_gap, g) : g;
    }
    home->modes.push_back(m);
    home->f_max = hz[m];
  }
  return chords;
}

// Simulated seconds of a chord: settling, then the window that separates its sinusoids.
double window(const Chord& c, const WaveOptions& o) {
  return c.min_gap > 0 ? o.beats / c.min_gap : 10.0 / c.f_min;
}

}  // namespace

void WaveOptions::validate() const {
  auto in = [](double v, double lo, double hi, const char* what) {
    if (!(v >= lo && v <= hi))
      throw InputError(std::string("transfer: wave ") + what + " must lie in [" +
                       std::to_string(lo) + ", " + std::to_string(hi) + "]");
  };
  in(cells_per_wavelength, 3, 64, "cells per wavelength");
  in(min_cells, 8, 4096, "min cells");
  in(pml_cells, 4, 64, "pml cells");
  in(margin_cells, 1, 32, "margin cells");
  in(courant, 0.05, 0.57, "courant number");
  in(beats, 0.5, 100, "beats");
  in(ramp_periods, 0, 100, "ramp periods");
  in(band_ratio, 1.01, 100, "band ratio");
  in(double(max_chord), 1, 1024, "max chord");
  if (!(max_memory >= 0) || !std::isfinite(max_memory))
    throw InputError("transfer: wave max memory must be finite and >= 0");
  in(retry_separation, 0, 1, "retry separation");
  in(grid_turns, 1, 4, "grid turns");
  if (!(max_cell_steps > 0) || !std::isfinite(max_cell_steps))
    throw InputError("transfer: wave max cell-steps must be finite and > 0");
}

std::vector<Chord> plan_chords(std::span<const double> hz, double settle, const WaveOptions& o) {
  o.validate();
  for (std::size_t i = 0; i < hz.size(); ++i) {
    if (!(hz[i] > 0) || !std::isfinite(hz[i]))
      throw InputError("transfer: mode " + std::to_string(i) + " has no positive frequency");
  }
  std::vector<std::size_t> order(hz.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return hz[a] < hz[b]; });
  std::vector<Chord> out;
  std::size_t end = order.size();
  while (end > 0) {  // bands from the top down
    const double top = hz[order[end - 1]];
    std::size_t begin = end;
    while (begin > 0 && hz[order[begin - 1]] * o.band_ratio > top) --begin;
    const std::vector<std::size_t> band(order.begin() + long(begin), order.begin() + long(end));
    const double f0 = hz[band.front()], width = top - f0;
    // The gap that minimises chords x (settle + beats / gap); never below 0.1 % of the top
    // frequency (closer modes go to different chords).
    std::vector<Chord> best;
    double best_cost = std::numeric_limits<double>::infinity();
    const double floor_gap = 1e-3 * top;
    for (std::size_t m = 1; m <= band.size(); ++m) {
      const double gap = std::max(width / double(m), floor_gap);
      std::vector<Chord> chords = pack(hz, band, gap, o.max_chord);
      double cost = 0;
      for (const Chord& c : chords) cost += settle + o.ramp_periods / c.f_min + window(c, o);
      if (cost < best_cost) best_cost = cost, best = std::move(chords);
      if (gap == floor_gap) break;
    }
    out.insert(out.end(), best.begin(), best.end());
    end = begin;
  }
  return out;
}

WaveGridSize wave_grid_size(const WaveLayout& layout, const Chord& chord, double c,
                            double surface_area, const WaveOptions& o) {
  const double *lo = layout.lo, *hi = layout.hi;
  WaveGridSize s;
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, hi[a] - lo[a]);
  s.h = std::min(c / (chord.f_max * o.cells_per_wavelength), longest / o.min_cells);
  if (!(s.h > 0)) throw InputError("transfer: the object has no extent");
  const double pad = o.pml_cells + o.margin_cells + 2;
  std::size_t n[3];
  double diagonal = 0;
  for (int a = 0; a < 3; ++a) {
    n[a] = std::size_t(std::ceil((hi[a] - lo[a]) / s.h)) + 1 + 2 * std::size_t(pad);
    diagonal += std::pow(double(n[a]) * s.h, 2);
  }
  s.nx = n[0], s.ny = n[1], s.nz = n[2];
  s.dt = o.courant * s.h / c;
  // Settle: the ramp, then twice the domain's diagonal for the start-up waves to leave.
  const double settle = o.ramp_periods / chord.f_min + 2.0 * std::sqrt(diagonal) / c;
  s.settle_steps = std::size_t(std::ceil(settle / s.dt));
  s.steps = s.settle_steps + std::size_t(std::ceil(window(chord, o) / s.dt));
  // Samples at >= 2.5 x the highest frequency tell the chord's sinusoids apart.
  s.stride = std::max<std::size_t>(1, std::size_t(std::floor(1.0 / (2.5 * chord.f_max * s.dt))));
  const double samples = double(s.steps - s.settle_steps) / double(s.stride) + 1;
  const double record = 2.0 * (double(n[0] * n[1] + n[1] * n[2] + n[0] * n[2]));
  const double J = double(chord.modes.size());
  s.turns = std::max<std::size_t>(1, layout.turns.size());
  s.bytes = double(s.cells()) * 6 * 4                          // p, two split parts, three w
            + record * samples * 2 * (4 + 2 * 8)               // float samples, double copies
            + double(s.turns) * record * J * 2 * 16            // each turn's separation
            + 2.0 * surface_area / (s.h * s.h) * (J * 8 + 68)  // blocked faces
            + double(s.steps) * J * 8;                         // drive, two series a mode
  return s;
}

}  // namespace chladni::precompute
