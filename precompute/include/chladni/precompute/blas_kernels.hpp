#pragma once
// Which kernels the BLAS runs. Debian 12's OpenBLAS (0.3.21) picks its kernels from the CPU
// model it knows; on a newer CPU (Intel Sapphire/Emerald Rapids) it falls back to its generic
// SSE3 "Prescott" kernels, and dense products run 5-6 times slower than with its AVX-512 ones.
// OPENBLAS_CORETYPE chooses them instead, but is read only when the library loads.
#include <string>

namespace chladni::precompute {

/// OpenBLAS's kernel set ("Haswell", "SkylakeX", "Prescott"...); empty for another BLAS.
std::string blas_core_name();

/// The OPENBLAS_CORETYPE that would serve this CPU better than the kernels OpenBLAS chose, or
/// empty: none is needed (OpenBLAS knows the CPU, or OPENBLAS_CORETYPE is set, or the BLAS is
/// not OpenBLAS, or the CPU has neither AVX2 nor AVX-512).
std::string better_blas_core();

}  // namespace chladni::precompute
