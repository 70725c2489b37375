#include "chladni/precompute/blas_kernels.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>

extern "C" char* openblas_get_corename() __attribute__((weak));

namespace chladni::precompute {

std::string blas_core_name() {
  if (!openblas_get_corename) return "";
  const char* name = openblas_get_corename();
  return name ? name : "";
}

std::string better_blas_core() {
  if (std::getenv("OPENBLAS_CORETYPE")) return "";  // the user's choice stands
  std::string core = blas_core_name();
  std::transform(core.begin(), core.end(), core.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  // The x86-64 fallbacks of a DYNAMIC_ARCH build, taken where it does not know the model.
  static const char* const kGeneric[] = {"prescott", "core2", "penryn", "dunnington",
                                         "nehalem",  "atom",  "unknown"};
  if (std::none_of(std::begin(kGeneric), std::end(kGeneric),
                   [&](const char* g) { return core == g; }))
    return "";
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl"))
    return "SkylakeX";
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "Haswell";
#endif
  return "";
}

}  // namespace chladni::precompute
