#pragma once
// The CPU filterbank inner loop, built once per instruction set (scalar, AVX2+FMA, AVX-512F) and
// chosen at run time, so one binary runs on any x86-64.
#include <cstdint>

#include "chladni/runtime/filterbank/filterbank.hpp"

namespace chladni::runtime::cpu {

/// Slots are grouped by 64 for excitation ordering: every tile size divides it.
constexpr uint32_t kGroup = 64;

struct KernelArgs {
  float* pr;
  float* pi;
  float* zr;
  float* zi;
  const float* g0;
  const float* g1;
  /// Gain ramps (nullptr `el`: none this call): target gains per slot (equal to g0/g1 where
  /// nothing ramps) and samples elapsed since each ramp began; the weight of the target at
  /// sample n is min(1, (el + n + 1) * inv_ramp).
  const float* t0;
  const float* t1;
  const float* el;
  float inv_ramp;
  uint32_t begin, end;  ///< slot range, multiples of kGroup (arrays are padded)
  /// Excitations with slot in [begin, end), sorted by (slot / kGroup, offset, slot).
  const Excitation* exc;
  uint32_t exc_count;
  uint32_t frames;
  int channels;  ///< 1 or 2
  float* out;    ///< frames * channels, overwritten with this range's sum
  float* lanes;  ///< scratch of frames * channels * 16 floats
  /// Driven slots (nullptr `in`: none): stream per slot (kNoStream: undriven), complex input gain,
  /// and the input rows, `frames` samples per stream.
  const uint32_t* src;
  const float* ar;
  const float* ai;
  const float* in;
};

using Kernel = void (*)(const KernelArgs&);

enum class Isa { Scalar, Avx2, Avx512 };
const char* isa_name(Isa isa);
bool isa_supported(Isa isa);
Isa best_isa();
Kernel kernel_for(Isa isa);

Kernel scalar_kernel();
Kernel avx2_kernel();    ///< nullptr when not built for this architecture
Kernel avx512_kernel();  ///< likewise

}  // namespace chladni::runtime::cpu
