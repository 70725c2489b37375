#include "chladni/runtime/thread_pool.hpp"

#include "denormals.hpp"

namespace chladni::runtime {

// Every worker checks in (done_) on every run before run() returns, so no worker can still be
// reading task_/context_/count_ while the next run writes them.

ThreadPool::ThreadPool(int threads) : workers_count_(threads > 1 ? threads - 1 : 0) {
  for (int i = 1; i < threads; ++i) workers_.emplace_back([this] { worker_loop(); });
}

ThreadPool::~ThreadPool() {
  quit_.store(true);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPool::drain() {
  for (int i; (i = next_.fetch_add(1, std::memory_order_relaxed)) < count_;) task_(context_, i);
}

void ThreadPool::worker_loop() {
  ScopedFlushDenormals ftz;
  uint32_t seen = 0;
  const int workers = workers_count_;
  for (;;) {
    generation_.wait(seen, std::memory_order_acquire);
    seen = generation_.load(std::memory_order_acquire);
    if (quit_.load()) return;
    drain();
    if (done_.fetch_add(1, std::memory_order_acq_rel) + 1 == workers) done_.notify_one();
  }
}

void ThreadPool::run(Task task, void* context, int count) {
  if (count <= 0) return;
  if (workers_.empty() || count == 1) {
    for (int i = 0; i < count; ++i) task(context, i);
    return;
  }
  task_ = task;
  context_ = context;
  count_ = count;
  next_.store(0, std::memory_order_relaxed);
  done_.store(0, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  drain();
  const int workers = workers_count_;
  for (int d; (d = done_.load(std::memory_order_acquire)) != workers;) done_.wait(d);
}

}  // namespace chladni::runtime
