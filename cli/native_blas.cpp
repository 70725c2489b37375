#include "native_blas.hpp"

#include <unistd.h>

#include <cstdlib>
#include <string>

#include "chladni/precompute/blas_kernels.hpp"

namespace chladni::cli {

void exec_with_native_blas(char** argv) {
  const std::string core = precompute::better_blas_core();
  if (core.empty()) return;
  // Set before the exec, so the new image (and any process it starts) loads with it, and a
  // second pass finds it set and goes on.
  if (setenv("OPENBLAS_CORETYPE", core.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
}

}  // namespace chladni::cli
