#pragma once
// The Vulkan filterbank: mode poles, states and gains stay resident in device memory; per
// process() only queued slot changes and the excitations go up, and only the output comes back.
#include <memory>
#include <vector>

#include "chladni/runtime/filterbank/filterbank.hpp"

namespace chladni::gpu {
class Buffer;
class Context;
class Pipeline;
class Sequence;
}  // namespace chladni::gpu

namespace chladni::runtime {

struct GpuFilterbankOptions {
  uint32_t capacity = 1u << 20;
  int channels = 1;
  uint32_t max_frames = 4096;  ///< lowered automatically to fit the scratch budget
  uint32_t max_excitations = 1u << 18;
  uint32_t workgroup_size = 64;
  /// Modes each invocation advances; 0 = auto: 32 on CPU devices (lavapipe: amortizes the
  /// per-sample subgroup reduction), 4 on GPUs (keeps enough invocations in flight).
  uint32_t modes_per_invocation = 0;
  uint64_t scratch_budget_bytes = 256ull << 20;
  /// Input streams for driven slots (stream rows of max_frames floats on the device).
  uint32_t max_streams = 0;
  uint32_t gain_ramp = 256;  ///< samples over which gain changes ramp (0: at once)
  /// process() submits its block and returns without waiting for the device, handing back
  /// samples max_frames() late: the device works while the caller goes on (an audio callback
  /// returns at once). Takes no GpuInputStage.
  bool pipelined = false;
};

/// Records device work that fills GpuFilterbank::input_buffer() for one process() call (a
/// stochastic excitation generated on the GPU), run in the same submission just before the
/// filterbank kernel.
class GpuInputStage {
 public:
  virtual ~GpuInputStage() = default;
  virtual void record(gpu::Sequence& sequence, uint32_t frames) = 0;
};

class GpuFilterbank final : public Filterbank {
 public:
  /// Throws gpu::NoDeviceError when no Vulkan device is usable.
  GpuFilterbank(std::shared_ptr<gpu::Context> context, const GpuFilterbankOptions& options = {});
  ~GpuFilterbank() override;

  std::string name() const override;
  uint32_t capacity() const override { return capacity_; }
  int channels() const override { return channels_; }
  uint32_t max_frames() const override { return max_frames_; }
  uint32_t max_excitations() const override { return max_excitations_; }
  uint32_t max_streams() const override { return max_streams_; }
  gpu::Context& context() { return *ctx_; }
  /// Device rows of the input streams, stream k at float offset k * frames of each call.
  gpu::Buffer& input_buffer() { return *inputs_; }
  /// A stage that writes the inputs on the device; process() calls with input.samples == nullptr
  /// and input.streams > 0 then record it instead of uploading (nullptr: none).
  void set_input_stage(GpuInputStage* stage);
  bool pipelined() const { return pipelined_; }

  void set_mode(uint32_t slot, std::complex<float> pole, const float gains[2]) override;
  void set_pole(uint32_t slot, std::complex<float> pole) override;
  void set_input(uint32_t slot, uint32_t stream, std::complex<float> gain) override;
  void set_gains(uint32_t slot, const float gains[2]) override;
  uint32_t gain_ramp() const override { return gain_ramp_; }
  void set_high_water(uint32_t slots) override;
  using Filterbank::process;
  void process(std::span<const Excitation> excitations, uint32_t frames, float* out,
               const DriveInput& input) override;
  std::complex<float> state(uint32_t slot) override;
  FilterbankTiming last_timing() const override { return timing_; }
  uint32_t latency() const override;
  GpuFilterbank* device() override { return this; }

 private:
  struct Update;
  Update& pending(uint32_t slot);
  void record_updates();
  void flush_updates(bool at_once = false);
  void ramps_at_once(uint32_t from_slot);  // queued ramps of slots >= from_slot become immediate
  void clear_updates();                    // after a submit has applied them
  void collect();                          // pipelined: waits for the block in flight
  uint32_t stage_excitations(std::span<const Excitation> excitations, uint32_t frames);
  void record_block(uint32_t frames, uint32_t excitations, uint32_t groups, bool driven,
                    bool from_stage);

  std::shared_ptr<gpu::Context> ctx_;
  uint32_t capacity_, channels_, max_frames_, max_excitations_, high_water_;
  uint32_t local_, mpi_, rows_per_group_, max_updates_, max_streams_;
  std::unique_ptr<gpu::Buffer> modes_, gains_, excitations_, scratch_, result_;
  std::unique_ptr<gpu::Buffer> updates_[2];  // one filled on the host while the device reads one
  std::unique_ptr<gpu::Buffer> drives_, inputs_, targets_;
  std::unique_ptr<gpu::Pipeline> filterbank_[2][2];  // [driven][ramp]
  std::unique_ptr<gpu::Pipeline> reduce_, apply_[2];
  uint32_t cur_ = 0;  // the update list being filled
  uint32_t gain_ramp_;
  // Samples processed, and the sample by which every ramp begun so far has ended: the ramping
  // kernel runs until then.
  uint64_t processed_ = 0, ramp_until_ = 0;
  std::vector<uint32_t> stream_;  // per slot, host mirror of the drive's stream
  uint32_t driven_ = 0;
  GpuInputStage* stage_ = nullptr;
  std::unique_ptr<gpu::Sequence> seq_;
  std::vector<uint32_t> pending_index_;  // per slot: index into the update list, or ~0
  uint32_t update_count_ = 0;
  FilterbankTiming timing_;
  // Pipelined mode: the block in flight, and the samples ready to hand back (a ring).
  bool pipelined_ = false, in_flight_ = false;
  uint32_t flight_frames_ = 0, flight_groups_ = 0;
  std::vector<float> fifo_;
  std::size_t fifo_head_ = 0, fifo_size_ = 0;
};

}  // namespace chladni::runtime
