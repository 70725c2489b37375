#pragma once
// A small deterministic generator for synthesis noise: the same seed gives the same stream on
// every platform and standard library (std::*_distribution do not promise that). SplitMix64
// (Steele, Lea and Flood, OOPSLA 2014); Box-Muller for normals.
#include <cmath>
#include <cstdint>
#include <numbers>

namespace chladni {

class Rng {
 public:
  explicit Rng(std::uint64_t seed = 1) : state_(seed) {}

  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n); n > 0.
  std::uint32_t index(std::uint32_t n) { return static_cast<std::uint32_t>(uniform() * n); }
  /// Standard normal.
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]: log stays finite
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  /// Exponential with the given rate (mean 1 / rate): waiting times of a Poisson process.
  double exponential(double rate) { return -std::log(1.0 - uniform()) / rate; }

 private:
  std::uint64_t state_;
};

}  // namespace chladni
