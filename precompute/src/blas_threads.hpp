#pragma once
// Holds OpenBLAS to one thread for a scope: where the callers already keep every core busy, or
// where the BLAS calls are too small to share (hmat-oss's leaf blocks), its worker threads only
// spin in sched_yield. Without OpenBLAS (weak symbols absent) it does nothing.

extern "C" void openblas_set_num_threads(int) __attribute__((weak));
extern "C" int openblas_get_num_threads() __attribute__((weak));

namespace chladni::precompute {

class SingleThreadedBlas {
 public:
  SingleThreadedBlas() {
    if (openblas_set_num_threads && openblas_get_num_threads) {
      saved_ = openblas_get_num_threads();
      openblas_set_num_threads(1);
    }
  }
  ~SingleThreadedBlas() {
    if (saved_ > 0) openblas_set_num_threads(saved_);
  }
  SingleThreadedBlas(const SingleThreadedBlas&) = delete;
  SingleThreadedBlas& operator=(const SingleThreadedBlas&) = delete;

 private:
  int saved_ = 0;
};

}  // namespace chladni::precompute
