#pragma once
// The named choices of the commands' options, parsed into the libraries' types: InputError
// naming the option and what it accepts otherwise.
#include <memory>
#include <string>

#include "chladni/core/audio_file.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/runtime/filterbank/make_filterbank.hpp"

namespace chladni::cli {

/// cpu, gpu, or auto where `allow_auto`.
gpu::DeviceChoice parse_backend(const std::string& name, const std::string& option,
                                bool allow_auto = false);

/// The --isa option: auto, scalar, avx2 or avx512, and one this processor runs.
runtime::CpuIsa parse_isa(const std::string& name);

/// A filterbank for the --backend NAME option: gpu without a device falls back to the CPU with
/// one warning on stderr. The request's other fields are taken as given.
std::unique_ptr<runtime::Filterbank> make_filterbank(const std::string& backend,
                                                     runtime::FilterbankRequest request);

/// Vulkan context for the transfer kernels: --transfer-backend gpu (warns and returns null
/// without a device), cpu (null) or auto (a hardware GPU when present, else null).
std::shared_ptr<gpu::Context> transfer_device(const std::string& backend);

/// auto, bem, wave or sources.
precompute::AcousticOptions::Method parse_transfer_method(const std::string& name,
                                                          const std::string& option);

/// The --format option of commands that write WAV: float, pcm24 or pcm16.
SampleFormat parse_sample_format(const std::string& name);

/// Prints "warning: MESSAGE" on stderr.
void warn(const std::string& message);

}  // namespace chladni::cli
