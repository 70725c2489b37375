#include "backend.hpp"

#include <cstdio>

#include "chladni/core/error.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"

namespace chladni::cli {
namespace {

runtime::CpuIsa parse_isa(const std::string& s) {
  if (s == "auto") return runtime::CpuIsa::Auto;
  if (s == "scalar") return runtime::CpuIsa::Scalar;
  if (s == "avx2") return runtime::CpuIsa::Avx2;
  if (s == "avx512") return runtime::CpuIsa::Avx512;
  throw InputError("--isa: unknown instruction set '" + s + "' (auto, scalar, avx2, avx512)");
}

}  // namespace

std::unique_ptr<runtime::Filterbank> make_filterbank(const BackendRequest& r) {
  if (r.backend == "gpu") {
    try {
      auto ctx = std::make_shared<gpu::Context>();
      runtime::GpuFilterbankOptions o;
      o.capacity = r.capacity;
      o.channels = r.channels;
      o.max_frames = r.max_frames;
      o.max_streams = r.max_streams;
      o.gain_ramp = r.gain_ramp;
      o.pipelined = r.pipelined;
      return std::make_unique<runtime::GpuFilterbank>(ctx, o);
    } catch (const gpu::NoDeviceError& e) {
      std::fprintf(stderr, "warning: %s; using the CPU filterbank instead\n", e.what());
    }
  } else if (r.backend != "cpu") {
    throw InputError("--backend: unknown backend '" + r.backend + "' (cpu, gpu)");
  }
  runtime::CpuFilterbankOptions o;
  o.capacity = r.capacity;
  o.channels = r.channels;
  o.threads = r.threads;
  o.isa = parse_isa(r.isa);
  o.max_frames = r.max_frames;
  o.gain_ramp = r.gain_ramp;
  if (!runtime::CpuFilterbank::supports(o.isa)) {
    throw InputError("--isa " + r.isa + ": not supported by this processor");
  }
  return std::make_unique<runtime::CpuFilterbank>(o);
}

std::shared_ptr<gpu::Context> transfer_device(const std::string& backend) {
  if (backend == "cpu") return nullptr;
  if (backend != "gpu" && backend != "auto")
    throw InputError("--transfer-backend: unknown backend '" + backend + "' (auto, cpu, gpu)");
  try {
    auto ctx = std::make_shared<gpu::Context>();
    const VkPhysicalDeviceType t = ctx->info().type;
    if (backend == "auto" && t != VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU &&
        t != VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU)
      return nullptr;
    return ctx;
  } catch (const gpu::NoDeviceError& e) {
    if (backend == "gpu")
      std::fprintf(stderr, "warning: %s; transfer kernels run on the CPU instead\n", e.what());
    return nullptr;
  }
}

precompute::AcousticOptions::Method parse_transfer_method(const std::string& name,
                                                          const std::string& option) {
  using M = precompute::AcousticOptions::Method;
  if (name == "auto") return M::Auto;
  if (name == "bem") return M::Bem;
  if (name == "sources") return M::Sources;
  if (name == "wave") return M::Wave;
  throw InputError(option + ": unknown method '" + name + "' (auto, bem, wave, sources)");
}

SampleFormat parse_sample_format(const std::string& name) {
  if (name == "float") return SampleFormat::Float32;
  if (name == "pcm24") return SampleFormat::Pcm24;
  if (name == "pcm16") return SampleFormat::Pcm16;
  throw InputError("--format must be float, pcm24 or pcm16");
}

}  // namespace chladni::cli
