#include "filterbank/cpu_kernels.hpp"

namespace chladni::runtime::cpu {

#if !CHLADNI_X86_64
Kernel avx2_kernel() {
  return nullptr;
}
Kernel avx512_kernel() {
  return nullptr;
}
#endif

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::Scalar:
      return "scalar";
    case Isa::Avx2:
      return "avx2";
    case Isa::Avx512:
      return "avx512";
  }
  return "?";
}

bool isa_supported(Isa isa) {
  switch (isa) {
    case Isa::Scalar:
      return true;
#if CHLADNI_X86_64
    case Isa::Avx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case Isa::Avx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("fma");
#else
    default:
      return false;
#endif
  }
  return false;
}

Isa best_isa() {
  if (isa_supported(Isa::Avx512)) return Isa::Avx512;
  if (isa_supported(Isa::Avx2)) return Isa::Avx2;
  return Isa::Scalar;
}

Kernel kernel_for(Isa isa) {
  switch (isa) {
    case Isa::Avx512:
      return avx512_kernel();
    case Isa::Avx2:
      return avx2_kernel();
    default:
      return scalar_kernel();
  }
}

}  // namespace chladni::runtime::cpu
