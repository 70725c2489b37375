// chladni devices: what the GPU and CPU backends would run on.
#include <cstdio>

#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "commands.hpp"

namespace chladni::cli {

void add_devices(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("devices", "List Vulkan devices and CPU instruction sets");
  cmd->callback([] {
    try {
      const auto devices = gpu::Context::list_devices();
      if (devices.empty()) std::printf("no Vulkan device with compute support\n");
      for (const auto& d : devices) {
        std::printf("vulkan [%u] %s (%s)\n", d.index, d.name.c_str(), d.type_name().c_str());
      }
      gpu::Context ctx;
      std::printf("selected: %s\n", ctx.describe().c_str());
    } catch (const gpu::NoDeviceError& e) {
      std::printf("no Vulkan device: %s\n", e.what());
    }
    runtime::CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
    std::printf("cpu filterbank: %s (avx2 %s, avx512 %s)\n", fb.name().c_str(),
                runtime::CpuFilterbank::supports(runtime::CpuIsa::Avx2) ? "yes" : "no",
                runtime::CpuFilterbank::supports(runtime::CpuIsa::Avx512) ? "yes" : "no");
  });
}

}  // namespace chladni::cli
