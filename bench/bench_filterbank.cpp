// Google Benchmark micro-benchmarks of one filterbank block, per CPU instruction set and on the
// GPU. `chladni bench` is the user-facing figure; this isolates the kernels.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <numbers>

#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"

using namespace chladni::runtime;

namespace {

void fill(Filterbank& fb, uint32_t n) {
  for (uint32_t s = 0; s < n; ++s) {
    const float g[2] = {1e-3f, 0.0f};
    fb.set_mode(s, pole(2 * std::numbers::pi * (40.0 + 17.0 * (s % 1000)), 2.0 + s % 13, 48000.0),
                g);
  }
  fb.set_high_water(n);
  std::vector<Excitation> kick;
  for (uint32_t s = 0; s < n; ++s) kick.push_back({s, 0, 1.0f, 0.0f});
  std::vector<float> out(fb.max_frames() * fb.channels());
  for (std::size_t k = 0; k < kick.size(); k += fb.max_excitations()) {
    fb.process(
        std::span(kick.data() + k, std::min<std::size_t>(fb.max_excitations(), kick.size() - k)),
        256, out.data());
  }
}

void run_blocks(benchmark::State& state, Filterbank& fb, uint32_t n) {
  fill(fb, n);
  std::vector<float> out(256 * fb.channels());
  for (auto _ : state) {
    fb.process({}, 256, out.data());
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["mode_samples_per_s"] =
      benchmark::Counter(double(n) * 256, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Cpu(benchmark::State& state, CpuIsa isa, int threads) {
  if (!CpuFilterbank::supports(isa)) {
    state.SkipWithError("instruction set not supported here");
    return;
  }
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  CpuFilterbank fb({.capacity = n, .channels = 1, .threads = threads, .isa = isa});
  run_blocks(state, fb, n);
}

void BM_Gpu(benchmark::State& state) {
  std::shared_ptr<chladni::gpu::Context> ctx;
  try {
    ctx = std::make_shared<chladni::gpu::Context>();
  } catch (const chladni::gpu::NoDeviceError& e) {
    state.SkipWithError(e.what());
    return;
  }
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  GpuFilterbank fb(ctx, {.capacity = n, .channels = 1});
  run_blocks(state, fb, n);
}

}  // namespace

BENCHMARK_CAPTURE(BM_Cpu, scalar_1t, CpuIsa::Scalar, 1)->Arg(10000)->UseRealTime();
BENCHMARK_CAPTURE(BM_Cpu, avx2_1t, CpuIsa::Avx2, 1)->Arg(10000)->Arg(100000)->UseRealTime();
BENCHMARK_CAPTURE(BM_Cpu, avx2_2t, CpuIsa::Avx2, 2)->Arg(100000)->Arg(1000000)->UseRealTime();
BENCHMARK_CAPTURE(BM_Cpu, avx512_2t, CpuIsa::Avx512, 2)->Arg(100000)->Arg(1000000)->UseRealTime();
BENCHMARK(BM_Gpu)->Arg(10000)->Arg(100000)->UseRealTime()->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
