#pragma once
// Splits [0, n) into contiguous chunks over threads (0: all cores). Enough for the dense loops of
// precompute; the FEM assembly and the block products keep their own tuned split.
#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace chladni::precompute {

template <class Fn>
void parallel_for(std::size_t n, int threads, Fn&& fn) {
  const std::size_t hw = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t t = std::min<std::size_t>(threads > 0 ? std::size_t(threads) : hw, n);
  if (t <= 1) {
    if (n > 0) fn(std::size_t{0}, n);
    return;
  }
  std::vector<std::thread> pool;
  for (std::size_t k = 0; k < t; ++k) {
    const std::size_t b = n * k / t, e = n * (k + 1) / t;
    pool.emplace_back([&fn, b, e] { fn(b, e); });
  }
  for (auto& th : pool) th.join();
}

}  // namespace chladni::precompute
