#pragma once
// The one factory of filterbanks, for the scene path, the commands and the C API: the CPU
// reference or the Vulkan filterbank, sized once for what will play on it.
#include <functional>
#include <memory>
#include <string>

#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"

namespace chladni::runtime {

struct FilterbankRequest {
  /// Cpu; Gpu (the chosen Vulkan device); Auto (a hardware GPU, else the CPU: on a CPU driver
  /// such as lavapipe the CPU filterbank is faster).
  gpu::DeviceChoice backend = gpu::DeviceChoice::Cpu;
  /// Gpu without a device: the CPU filterbank after one `warn`, or gpu::NoDeviceError.
  bool gpu_falls_back = true;
  std::function<void(const std::string&)> warn;  ///< optional
  uint32_t capacity = 1u << 20;                  ///< mode slots
  int channels = 1;
  int threads = 0;             ///< cpu: 0 for all hardware threads
  CpuIsa isa = CpuIsa::Auto;   ///< cpu: InputError where the processor lacks it
  uint32_t max_frames = 4096;  ///< frames per process() call
  uint32_t max_streams = 0;    ///< gpu: input streams of driven slots (PhISEM voices)
  uint32_t gain_ramp = 256;    ///< samples over which gain changes ramp (0: at once)
  bool pipelined = false;      ///< gpu: process() returns before the device is done
  /// Gpu or Auto: this device (an application's, shared) rather than one opened here.
  std::shared_ptr<gpu::Context> device;
};

std::unique_ptr<Filterbank> make_filterbank(const FilterbankRequest& request);

/// auto, scalar, avx2 or avx512; InputError naming `option` otherwise.
CpuIsa parse_cpu_isa(const std::string& name, const std::string& option = "--isa");

}  // namespace chladni::runtime
