#pragma once
// Persistent worker threads for the CPU filterbank. run() hands out task indices to the workers
// and the calling thread; it neither allocates nor takes locks (workers sleep on atomic waits).
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace chladni::runtime {

class ThreadPool {
 public:
  using Task = void (*)(void* context, int index);
  /// `threads` counts the calling thread; 1 means no workers.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return workers_count_ + 1; }
  /// Runs task(context, i) for i in [0, count), spread over all threads; returns when all are done.
  void run(Task task, void* context, int count);

 private:
  void worker_loop();
  void drain();
  int workers_count_ = 0;
  std::vector<std::thread> workers_;
  std::atomic<uint32_t> generation_{0};
  std::atomic<int> next_{0};
  std::atomic<int> done_{0};  // workers finished with the current run
  std::atomic<bool> quit_{false};
  Task task_ = nullptr;
  void* context_ = nullptr;
  int count_ = 0;
};

}  // namespace chladni::runtime
