#pragma once
// A synthetic sounding object for the runtime's benchmarks: log-spaced modes from 60 Hz to
// 16 kHz with decay growing with frequency, random mode shapes at random surface points. The
// runtime's cost depends on the counts, not on where the modes came from.
#include <cmath>
#include <numbers>

#include "chladni/core/modal_model.hpp"
#include "chladni/core/random.hpp"

namespace chladni::bench {

inline ModalModel synthetic_object(std::size_t modes, std::size_t points, uint64_t seed = 3) {
  ModalModel m;
  m.name = "synthetic";
  Rng rng(seed);
  for (std::size_t i = 0; i < modes; ++i) {
    const double x = modes > 1 ? double(i) / double(modes - 1) : 0.0;
    const double hz = 60.0 * std::pow(16000.0 / 60.0, x);
    m.omega.push_back(2 * std::numbers::pi * hz);
    m.decay.push_back(1.0 + 2e-4 * hz);
    m.radiation.push_back(1e-4);
  }
  for (std::size_t p = 0; p < points; ++p) {
    m.points.push_back({rng.normal(), rng.normal(), rng.normal()});
    m.normals.push_back({0, 0, 1});
  }
  for (std::size_t i = 0; i < modes * points; ++i)
    m.shapes.push_back({rng.normal(), rng.normal(), rng.normal()});
  return m;
}

}  // namespace chladni::bench
