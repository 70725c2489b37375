#pragma once
// What the benchmark programs share: wall-clock seconds, and arguments parsed or a usage error.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>

namespace chladni::bench {

using clock_type = std::chrono::steady_clock;

inline double seconds_since(clock_type::time_point t0) {
  return std::chrono::duration<double>(clock_type::now() - t0).count();
}

/// parse(argc, argv); whatever it throws is a usage error: the message, and exit status 2.
template <class Parse>
auto parse_or_exit(Parse parse, int argc, char** argv) {
  try {
    return parse(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::exit(2);
  }
}

}  // namespace chladni::bench
