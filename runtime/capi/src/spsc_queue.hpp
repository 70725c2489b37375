#pragma once
// A bounded single-producer single-consumer queue: one thread pushes (a game thread), one pops
// (the audio thread); neither allocates, locks or waits. Storage is fixed at construction.
#include <atomic>
#include <cstddef>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

namespace chladni::runtime {

/// The index mask of a ring holding `capacity` items rounded up to a power of two; `what` names
/// the ring in the error for a capacity outside [1, 2^30].
inline std::size_t ring_mask(std::size_t capacity, const char* what) {
  if (capacity == 0 || capacity > (std::size_t{1} << 30))
    throw std::invalid_argument(std::string(what) + " capacity must be in [1, 2^30]");
  std::size_t n = 1;
  while (n < capacity) n <<= 1;
  return n - 1;
}

template <class T>
class SpscQueue {
 public:
  /// Holds up to `capacity` items (rounded up to a power of two).
  explicit SpscQueue(std::size_t capacity)
      : mask_(ring_mask(capacity, "queue")), items_(std::make_unique<T[]>(mask_ + 1)) {}
  /// Producer: false (and nothing queued) when full.
  bool push(const T& item) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_cache_ > mask_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail - head_cache_ > mask_) return false;
    }
    items_[tail & mask_] = item;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  /// Consumer: the oldest item, or null when empty. Stays valid until pop().
  const T* front() {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head == tail_cache_) return nullptr;
    }
    return &items_[head & mask_];
  }
  /// Consumer: drops the item front() returned.
  void pop() { head_.store(head_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }
  std::size_t capacity() const { return mask_ + 1; }

 private:
  std::size_t mask_;  // before items_, which is sized from it
  std::unique_ptr<T[]> items_;
  // Each side's index on its own cache line, with its cached view of the other side's.
  alignas(64) std::atomic<std::size_t> head_{0};
  std::size_t tail_cache_ = 0;
  alignas(64) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;
};

/// A bounded single-producer single-consumer ring of floats, written and read in runs: one
/// thread writes (the control thread's paper sheet), one reads (the audio thread).
class SpscRing {
 public:
  explicit SpscRing(std::size_t capacity)
      : mask_(ring_mask(capacity, "ring")), items_(std::make_unique<float[]>(mask_ + 1)) {}
  /// Producer: room for this many floats.
  std::size_t room() const {
    return mask_ + 1 -
           (tail_.load(std::memory_order_relaxed) - head_.load(std::memory_order_acquire));
  }
  /// Producer: writes all `n` floats, or nothing (false) when they do not fit.
  bool write(const float* x, std::size_t n) {
    if (n > room()) return false;
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    for (std::size_t i = 0; i < n; ++i) items_[(tail + i) & mask_] = x[i];
    tail_.store(tail + n, std::memory_order_release);
    return true;
  }
  /// Consumer: floats written and not yet consumed.
  std::size_t size() const {
    return tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_relaxed);
  }
  /// Consumer: the i-th unread float (i < size()).
  float at(std::size_t i) const {
    return items_[(head_.load(std::memory_order_relaxed) + i) & mask_];
  }
  /// Consumer: drops the oldest `n` (<= size()).
  void consume(std::size_t n) {
    head_.store(head_.load(std::memory_order_relaxed) + n, std::memory_order_release);
  }

 private:
  std::size_t mask_;  // before items_, which is sized from it
  std::unique_ptr<float[]> items_;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace chladni::runtime
