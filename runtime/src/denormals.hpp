#pragma once
// Flush-to-zero / denormals-are-zero for the calling thread while in scope: decaying resonator
// states must not fall into slow denormal arithmetic.
#if defined(__x86_64__) || defined(_M_X64)
#include <xmmintrin.h>
#endif

namespace chladni::runtime {

class ScopedFlushDenormals {
 public:
#if defined(__x86_64__) || defined(_M_X64)
  ScopedFlushDenormals() : saved_(_mm_getcsr()) {
    _mm_setcsr(saved_ | 0x8040);
  }  // FTZ | DAZ
  ~ScopedFlushDenormals() {
    _mm_setcsr(saved_);
  }

 private:
  unsigned saved_;
#endif
};

}  // namespace chladni::runtime
