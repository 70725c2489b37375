#pragma once
// The shaker bank's GPU excitation (internal to runtime/src/phisem).
#include <memory>
#include <span>

#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"
#include "chladni/gpu/sequence.hpp"
#include "chladni/kernels/phisem.spv.h"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"

namespace chladni::runtime {

// The GPU excitation: parameters and states in mapped buffers, one dispatch per block recorded
// into the GPU filterbank's submission ahead of its kernel.
class ShakerBank::GpuStage final : public GpuInputStage {
 public:
  GpuStage(GpuFilterbank& fb, uint32_t max_voices, uint32_t max_shakes) : fb_(fb) {
    gpu::Context& c = fb.context();
    params = std::make_unique<gpu::Buffer>(c, uint64_t{max_voices} * 32, gpu::Memory::HostVisible);
    states = std::make_unique<gpu::Buffer>(c, uint64_t{max_voices} * 32, gpu::Memory::HostVisible);
    shakes =
        std::make_unique<gpu::Buffer>(c, uint64_t{max_shakes + 1} * 16, gpu::Memory::HostVisible);
    pipeline = std::make_unique<gpu::Pipeline>(c, std::span(k_phisem_spv), 4, 16);
    pipeline->bind(0, *params);
    pipeline->bind(1, *states);
    pipeline->bind(2, *shakes);
    pipeline->bind(3, fb.input_buffer());
  }
  void record(gpu::Sequence& seq, uint32_t frames) override {
    const uint32_t push[4] = {voices, frames, shake_count, 0};
    seq.dispatch(*pipeline, (voices + 63) / 64, push, sizeof(push));
  }
  PhisemParams* param_data() { return static_cast<PhisemParams*>(params->data()); }
  PhisemState* state_data() { return static_cast<PhisemState*>(states->data()); }
  uint32_t* shake_data() { return static_cast<uint32_t*>(shakes->data()); }

  GpuFilterbank& fb_;
  std::unique_ptr<gpu::Buffer> params, states, shakes;
  std::unique_ptr<gpu::Pipeline> pipeline;
  uint32_t voices = 0, shake_count = 0;
};

}  // namespace chladni::runtime
