#pragma once
// Wall-clock seconds since a steady_clock time point, for the stage times precompute reports.
#include <chrono>

namespace chladni::precompute {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace chladni::precompute
