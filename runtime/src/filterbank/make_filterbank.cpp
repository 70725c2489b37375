#include "chladni/runtime/filterbank/make_filterbank.hpp"

#include <stdexcept>

#include "chladni/core/error.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"

namespace chladni::runtime {
namespace {

std::unique_ptr<Filterbank> gpu_filterbank(std::shared_ptr<gpu::Context> ctx,
                                           const FilterbankRequest& r) {
  GpuFilterbankOptions o;
  o.capacity = r.capacity;
  o.channels = r.channels;
  o.max_frames = r.max_frames;
  o.max_streams = r.max_streams;
  o.gain_ramp = r.gain_ramp;
  o.pipelined = r.pipelined;
  return std::make_unique<GpuFilterbank>(std::move(ctx), o);
}

// A request the CPU filterbank refuses (an instruction set this processor lacks, a zero
// capacity) is the caller's input.
std::unique_ptr<Filterbank> cpu_filterbank(const FilterbankRequest& r) {
  CpuFilterbankOptions o;
  o.capacity = r.capacity;
  o.channels = r.channels;
  o.threads = r.threads;
  o.isa = r.isa;
  o.max_frames = r.max_frames;
  o.gain_ramp = r.gain_ramp;
  try {
    return std::make_unique<CpuFilterbank>(o);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
}

}  // namespace

std::unique_ptr<Filterbank> make_filterbank(const FilterbankRequest& r) {
  using gpu::DeviceChoice;
  if (r.device && r.backend != DeviceChoice::Cpu) return gpu_filterbank(r.device, r);
  if (r.backend == DeviceChoice::Gpu && !r.gpu_falls_back)
    return gpu_filterbank(std::make_shared<gpu::Context>(), r);  // NoDeviceError passes on
  const auto warn = [&](const std::string& why) {
    if (r.warn) r.warn(why + "; using the CPU filterbank instead");
  };
  if (auto ctx = gpu::open_device(r.backend, warn)) return gpu_filterbank(std::move(ctx), r);
  return cpu_filterbank(r);
}

CpuIsa parse_cpu_isa(const std::string& s, const std::string& option) {
  if (s == "auto") return CpuIsa::Auto;
  if (s == "scalar") return CpuIsa::Scalar;
  if (s == "avx2") return CpuIsa::Avx2;
  if (s == "avx512") return CpuIsa::Avx512;
  throw InputError(option + ": unknown instruction set '" + s + "' (auto, scalar, avx2, avx512)");
}

}  // namespace chladni::runtime
