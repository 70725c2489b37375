#pragma once
// Filterbank construction for the CLI: "cpu" or "gpu"; a missing Vulkan device turns "gpu" into
// the CPU path with one warning on stderr.
#include <memory>
#include <string>

#include "chladni/core/audio_file.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"

namespace chladni::gpu {
class Context;
}

namespace chladni::cli {

struct BackendRequest {
  std::string backend = "cpu";  ///< "cpu" | "gpu"
  uint32_t capacity = 1u << 20;
  int channels = 1;
  int threads = 0;
  std::string isa = "auto";  ///< cpu only: auto | scalar | avx2 | avx512
  uint32_t max_frames = 4096;
  uint32_t max_streams = 0;  ///< input streams of driven slots (PhISEM voices)
  uint32_t gain_ramp = 256;  ///< samples over which gain changes ramp (0: at once)
  bool pipelined = false;    ///< gpu only: process() returns before the device is done
};

std::unique_ptr<runtime::Filterbank> make_filterbank(const BackendRequest& request);

/// Vulkan context for the transfer kernels: "gpu" (warns and returns null without a device),
/// "cpu" (null) or "auto" (a discrete or integrated GPU when present, else null: on a CPU
/// driver such as lavapipe the double-precision CPU kernels are as fast, see PERFORMANCE.md).
std::shared_ptr<gpu::Context> transfer_device(const std::string& backend);

/// auto, bem or sources (InputError naming `option` otherwise).
precompute::AcousticOptions::Method parse_transfer_method(const std::string& name,
                                                          const std::string& option);

/// The --format option of commands that write WAV: float, pcm24 or pcm16 (InputError otherwise).
SampleFormat parse_sample_format(const std::string& name);

}  // namespace chladni::cli
