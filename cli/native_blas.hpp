#pragma once
// Runs the process again with OPENBLAS_CORETYPE set where Debian's OpenBLAS does not know this
// CPU and would run its generic kernels (precompute/blas_kernels.hpp): the variable is read only
// when the library loads. Returns (doing nothing) where no better kernels exist, where the user
// set OPENBLAS_CORETYPE, or where the exec fails.
namespace chladni::cli {

void exec_with_native_blas(char** argv);

}  // namespace chladni::cli
