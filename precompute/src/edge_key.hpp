#pragma once
#include <cstdint>

namespace chladni::precompute {

/// An undirected edge's key for hashing: its two node numbers, the smaller in the high half.
inline std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
}

}  // namespace chladni::precompute
