// AVX2 + FMA build of the filterbank loop (compiled with -mavx2 -mfma; called only when the
// processor has them).
#include <immintrin.h>

#include "filterbank/cpu_kernel_impl.hpp"

namespace chladni::runtime::cpu {
namespace {
struct Avx2 {
  using V = __m256;
  static constexpr int W = 8;
  static V load(const float* p) { return _mm256_load_ps(p); }
  static void store(float* p, V v) { _mm256_store_ps(p, v); }
  static V set1(float x) { return _mm256_set1_ps(x); }
  static V zero() { return _mm256_setzero_ps(); }
  static V add(V a, V b) { return _mm256_add_ps(a, b); }
  static V min(V a, V b) { return _mm256_min_ps(a, b); }
  static V sub(V a, V b) { return _mm256_sub_ps(a, b); }
  static V mul(V a, V b) { return _mm256_mul_ps(a, b); }
  static V fmadd(V a, V b, V c) { return _mm256_fmadd_ps(a, b, c); }
  static V fmsub(V a, V b, V c) { return _mm256_fmsub_ps(a, b, c); }
};
}  // namespace

Kernel avx2_kernel() {
  return &kernel_entry<Avx2, 4>;
}

}  // namespace chladni::runtime::cpu
