#include "parse_choices.hpp"

#include <cstdio>

#include "chladni/core/error.hpp"

namespace chladni::cli {

gpu::DeviceChoice parse_backend(const std::string& name, const std::string& option,
                                bool allow_auto) {
  if (name == "cpu") return gpu::DeviceChoice::Cpu;
  if (name == "gpu") return gpu::DeviceChoice::Gpu;
  if (allow_auto && name == "auto") return gpu::DeviceChoice::Auto;
  throw InputError(option + ": unknown backend '" + name + "' (" +
                   (allow_auto ? "auto, cpu, gpu" : "cpu, gpu") + ")");
}

runtime::CpuIsa parse_isa(const std::string& name) {
  const runtime::CpuIsa isa = runtime::parse_cpu_isa(name, "--isa");
  if (!runtime::CpuFilterbank::supports(isa))
    throw InputError("--isa " + name + ": not supported by this processor");
  return isa;
}

std::unique_ptr<runtime::Filterbank> make_filterbank(const std::string& backend,
                                                     runtime::FilterbankRequest r) {
  r.backend = parse_backend(backend, "--backend");
  r.warn = warn;
  return runtime::make_filterbank(r);
}

std::shared_ptr<gpu::Context> transfer_device(const std::string& backend) {
  return gpu::open_device(
      parse_backend(backend, "--transfer-backend", true),
      [](const std::string& why) { warn(why + "; transfer kernels run on the CPU instead"); });
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

void warn(const std::string& message) {
  std::fprintf(stderr, "warning: %s\n", message.c_str());
}

}  // namespace chladni::cli
