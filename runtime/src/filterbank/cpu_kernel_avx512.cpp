// AVX-512F build of the filterbank loop (compiled with -mavx512f -mfma; called only when the
// processor has AVX-512F).
#include <immintrin.h>

#include "filterbank/cpu_kernel_impl.hpp"

namespace chladni::runtime::cpu {
namespace {
struct Avx512 {
  using V = __m512;
  static constexpr int W = 16;
  static V load(const float* p) { return _mm512_load_ps(p); }
  static void store(float* p, V v) { _mm512_store_ps(p, v); }
  static V set1(float x) { return _mm512_set1_ps(x); }
  static V zero() { return _mm512_setzero_ps(); }
  static V add(V a, V b) { return _mm512_add_ps(a, b); }
  static V min(V a, V b) { return _mm512_min_ps(a, b); }
  static V sub(V a, V b) { return _mm512_sub_ps(a, b); }
  static V mul(V a, V b) { return _mm512_mul_ps(a, b); }
  static V fmadd(V a, V b, V c) { return _mm512_fmadd_ps(a, b, c); }
  static V fmsub(V a, V b, V c) { return _mm512_fmsub_ps(a, b, c); }
};
}  // namespace

Kernel avx512_kernel() {
  return &kernel_entry<Avx512, 4>;
}

}  // namespace chladni::runtime::cpu
