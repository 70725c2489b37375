#pragma once
// Runs of free slots within a filterbank lease, for users whose voices come and go (a
// ShakerBank's, a ContactBank's): sorted by first slot and merged, with the capacity reserved
// up front, so that taking and giving back never allocate (the audio thread does both).
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace chladni::runtime {

class SlotRuns {
 public:
  /// Room for `runs` runs: one per voice that may be out at once, plus one.
  void reserve(std::size_t runs) { runs_.reserve(runs); }
  /// `count` consecutive slots from the front of the first run that holds them; ~0u when none
  /// does.
  uint32_t take(uint32_t count) noexcept {
    for (std::size_t k = 0; k < runs_.size(); ++k) {
      auto& [first, n] = runs_[k];
      if (n < count) continue;
      const uint32_t at = first;
      first += count;
      n -= count;
      if (n == 0) runs_.erase(runs_.begin() + std::ptrdiff_t(k));
      return at;
    }
    return ~0u;
  }
  /// Gives a run back, merged with its neighbours (within the reserved capacity).
  void give(uint32_t first, uint32_t count) noexcept {
    if (count == 0) return;
    auto it = std::lower_bound(runs_.begin(), runs_.end(), std::pair(first, 0u));
    it = runs_.insert(it, {first, count});
    if (auto next = it + 1; next != runs_.end() && it->first + it->second == next->first) {
      it->second += next->second;
      runs_.erase(next);
    }
    if (it != runs_.begin()) {
      auto prev = it - 1;
      if (prev->first + prev->second == it->first) {
        prev->second += it->second;
        runs_.erase(it);
      }
    }
  }
  /// The longest run's length (0 when none is free).
  uint32_t largest() const {
    uint32_t n = 0;
    for (const auto& run : runs_) n = std::max(n, run.second);
    return n;
  }

 private:
  std::vector<std::pair<uint32_t, uint32_t>> runs_;
};

}  // namespace chladni::runtime
