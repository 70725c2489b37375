// Portable scalar build of the filterbank loop (also the reference for the SIMD builds).
#include "filterbank/cpu_kernel_impl.hpp"

namespace chladni::runtime::cpu {
namespace {
struct Scalar {
  using V = float;
  static constexpr int W = 1;
  static V load(const float* p) { return *p; }
  static void store(float* p, V v) { *p = v; }
  static V set1(float x) { return x; }
  static V zero() { return 0.0f; }
  static V add(V a, V b) { return a + b; }
  static V min(V a, V b) { return a < b ? a : b; }
  static V sub(V a, V b) { return a - b; }
  static V mul(V a, V b) { return a * b; }
  // Plain multiply-add: std::fma without hardware FMA is a slow software routine.
  static V fmadd(V a, V b, V c) { return a * b + c; }
  static V fmsub(V a, V b, V c) { return a * b - c; }
};
}  // namespace

Kernel scalar_kernel() {
  return &kernel_entry<Scalar, 8>;
}

}  // namespace chladni::runtime::cpu
