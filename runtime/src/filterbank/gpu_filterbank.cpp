#include "chladni/runtime/filterbank/gpu_filterbank.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"
#include "chladni/gpu/sequence.hpp"
#include "chladni/kernels/apply_updates.spv.h"
#include "chladni/kernels/filterbank.spv.h"
#include "chladni/kernels/reduce.spv.h"

namespace chladni::runtime {
namespace {

constexpr uint32_t kNone = ~0u;
constexpr uint32_t kReduceChunk = 64;  // rows summed per reduce invocation

uint32_t div_up(uint64_t a, uint64_t b) {
  return static_cast<uint32_t>((a + b - 1) / b);
}

struct FilterbankPush {
  uint32_t mode_count, samples, exc_count, ramp;
};
constexpr uint32_t kGains = 2, kRampTo = 16;  // Update flags (apply_updates.comp)
struct ReducePush {
  uint32_t src_offset, dst_offset, rows, count, chunk, final_pass;
};

}  // namespace

struct GpuFilterbank::Update {
  uint32_t slot, flags;
  float gain[2];
  float pz[4];
  uint32_t stream;
  float input[2];
  uint32_t pad;
};

GpuFilterbank::GpuFilterbank(std::shared_ptr<gpu::Context> ctx, const GpuFilterbankOptions& o)
    : ctx_(std::move(ctx)),
      capacity_(o.capacity),
      channels_(static_cast<uint32_t>(o.channels)),
      max_excitations_(o.max_excitations),
      high_water_(o.capacity),
      local_(o.workgroup_size),
      mpi_(o.modes_per_invocation),
      max_streams_(o.max_streams),
      gain_ramp_(o.gain_ramp),
      pipelined_(o.pipelined) {
  static_assert(sizeof(Update) == 48, "matches apply_updates.comp");
  if (!ctx_) throw std::invalid_argument("GpuFilterbank needs a Vulkan context");
  if (capacity_ == 0) throw std::invalid_argument("filterbank capacity must be > 0");
  if (mpi_ == 0) mpi_ = ctx_->info().type == VK_PHYSICAL_DEVICE_TYPE_CPU ? 32 : 4;
  if (mpi_ > 256) throw std::invalid_argument("modes_per_invocation must be at most 256");
  if (channels_ != 1 && channels_ != 2) throw std::invalid_argument("channels must be 1 or 2");
  gpu::Context& c = *ctx_;
  if (!c.subgroup_arithmetic()) {
    throw gpu::NoDeviceError(c.info().name + " lacks subgroup arithmetic in compute shaders");
  }
  const VkPhysicalDeviceLimits& lim = c.limits();
  local_ = std::min(local_, lim.maxComputeWorkGroupSize[0]);
  local_ = std::min(local_, lim.maxComputeWorkGroupInvocations);
  // Subgroups per workgroup bound the partial rows each workgroup writes.
  rows_per_group_ = div_up(local_, c.subgroup_size());
  const uint32_t group_modes = local_ * mpi_;
  const uint32_t groups = div_up(capacity_, group_modes);
  if (groups > lim.maxComputeWorkGroupCount[0]) {
    throw gpu::Error("filterbank capacity needs more workgroups than the device allows");
  }
  const uint64_t rows = uint64_t{groups} * rows_per_group_;
  // Scratch holds rows x frames x channels partials plus the first reduce level.
  const uint64_t per_frame = (rows + div_up(rows, kReduceChunk)) * channels_ * sizeof(float);
  const uint64_t budget = std::min<uint64_t>(o.scratch_budget_bytes, lim.maxStorageBufferRange);
  // Offsets share 16 bits with the mode index in the shader's excitation entries.
  max_frames_ =
      static_cast<uint32_t>(std::min<uint64_t>({o.max_frames, budget / per_frame, 65535}));
  if (max_frames_ < 1) throw gpu::Error("filterbank capacity too large for the scratch budget");

  const uint64_t mode_bytes = uint64_t{groups} * group_modes * 16;
  if (mode_bytes > lim.maxStorageBufferRange) {
    throw gpu::Error("filterbank capacity exceeds the device's storage buffer range");
  }
  modes_ = std::make_unique<gpu::Buffer>(c, mode_bytes, gpu::Memory::DeviceLocal);
  gains_ = std::make_unique<gpu::Buffer>(c, uint64_t{groups} * group_modes * 8,
                                         gpu::Memory::DeviceLocal);
  targets_ = std::make_unique<gpu::Buffer>(c, uint64_t{groups} * group_modes * 16,
                                           gpu::Memory::DeviceLocal);
  // One spare entry: the shader may read the entry after its list.
  excitations_ = std::make_unique<gpu::Buffer>(c, (uint64_t{max_excitations_} + 1) * 16,
                                               gpu::Memory::HostVisible);
  scratch_ = std::make_unique<gpu::Buffer>(c, per_frame * max_frames_, gpu::Memory::DeviceLocal);
  result_ = std::make_unique<gpu::Buffer>(c, uint64_t{max_frames_} * channels_ * sizeof(float),
                                          gpu::Memory::HostVisible);
  max_updates_ = std::min(capacity_, 1u << 16);
  for (auto& u : updates_)
    u = std::make_unique<gpu::Buffer>(c, uint64_t{max_updates_} * sizeof(Update),
                                      gpu::Memory::HostVisible);
  drives_ = std::make_unique<gpu::Buffer>(c, uint64_t{groups} * group_modes * 16,
                                          gpu::Memory::DeviceLocal);
  const uint64_t input_bytes = uint64_t{max_streams_} * max_frames_ * sizeof(float);
  if (input_bytes > lim.maxStorageBufferRange) {
    throw gpu::Error("filterbank input streams exceed the device's storage buffer range");
  }
  // Mapped, so that inputs made on the host are written in place; a GpuInputStage writes it too.
  inputs_ = std::make_unique<gpu::Buffer>(c, std::max<uint64_t>(input_bytes, 16),
                                          gpu::Memory::HostVisible);
  modes_->zero();
  gains_->zero();
  targets_->zero();
  {
    std::vector<uint32_t> none(uint64_t{groups} * group_modes * 4, 0);
    for (std::size_t i = 0; i < none.size(); i += 4) none[i] = kNone;
    drives_->upload(none.data(), none.size() * sizeof(uint32_t));
  }

  auto make_filterbank = [&](bool driven, bool ramp) {
    const gpu::SpecConstant spec[] = {{0, local_},           {1, mpi_},
                                      {2, channels_},        {3, rows_per_group_},
                                      {4, driven ? 1u : 0u}, {5, ramp ? 1u : 0u}};
    auto p = std::make_unique<gpu::Pipeline>(c, std::span(k_filterbank_spv), 7,
                                             sizeof(FilterbankPush), spec);
    p->bind(0, *modes_);
    p->bind(1, *gains_);
    p->bind(2, *excitations_);
    p->bind(3, *scratch_);
    p->bind(4, *drives_);
    p->bind(5, *inputs_);
    p->bind(6, *targets_);
    return p;
  };
  for (int driven = 0; driven < 2; ++driven)
    for (int ramp = 0; ramp < 2; ++ramp) filterbank_[driven][ramp] = make_filterbank(driven, ramp);
  reduce_ = std::make_unique<gpu::Pipeline>(c, std::span(k_reduce_spv), 2, sizeof(ReducePush));
  reduce_->bind(0, *scratch_);
  reduce_->bind(1, *result_);
  for (int k = 0; k < 2; ++k) {
    apply_[k] =
        std::make_unique<gpu::Pipeline>(c, std::span(k_apply_updates_spv), 5, 2 * sizeof(uint32_t));
    apply_[k]->bind(0, *modes_);
    apply_[k]->bind(1, *gains_);
    apply_[k]->bind(2, *updates_[k]);
    apply_[k]->bind(3, *drives_);
    apply_[k]->bind(4, *targets_);
  }
  seq_ = std::make_unique<gpu::Sequence>(c, 4);
  if (pipelined_) {
    // The output lags by max_frames: that many samples of silence come first.
    fifo_.assign(2 * std::size_t{max_frames_} * channels_, 0.0f);
    fifo_size_ = std::size_t{max_frames_} * channels_;
  }
  pending_index_.assign(capacity_, kNone);
  stream_.assign(capacity_, kNone);
}

GpuFilterbank::~GpuFilterbank() {
  if (seq_ && seq_->pending()) seq_->wait();
}

uint32_t GpuFilterbank::latency() const {
  return pipelined_ ? max_frames_ : 0;
}

void GpuFilterbank::set_input_stage(GpuInputStage* stage) {
  // A stage's host-side state (a particle count read after each block) would race the block in
  // flight.
  if (stage && pipelined_)
    throw std::invalid_argument("a pipelined GPU filterbank takes no device input stage");
  stage_ = stage;
}

// Waits for the block in flight and queues its samples (pipelined mode).
void GpuFilterbank::collect() {
  if (!in_flight_) return;
  seq_->wait();
  in_flight_ = false;
  timing_.gpu_ms = seq_->elapsed_ns(0, 2) * 1e-6;
  timing_.kernel_ms = flight_groups_ ? seq_->elapsed_ns(0, 1) * 1e-6 : 0.0;
  const std::size_t n = std::size_t{flight_frames_} * channels_;
  const auto* r = static_cast<const float*>(result_->data());
  for (std::size_t i = 0; i < n; ++i) fifo_[(fifo_head_ + fifo_size_ + i) % fifo_.size()] = r[i];
  fifo_size_ += n;
}

std::string GpuFilterbank::name() const {
  return "gpu (" + ctx_->describe() + ")";
}

GpuFilterbank::Update& GpuFilterbank::pending(uint32_t slot) {
  if (slot >= capacity_) throw std::out_of_range("filterbank slot out of range");
  auto* list = static_cast<Update*>(updates_[cur_]->data());
  uint32_t& idx = pending_index_[slot];
  if (idx == kNone) {
    if (update_count_ == max_updates_) flush_updates(true);
    idx = update_count_++;
    list[idx] = Update{slot, 0, {0, 0}, {0, 0, 0, 0}, kNone, {0, 0}, 0};
  }
  return list[idx];
}

void GpuFilterbank::set_mode(uint32_t slot, std::complex<float> p, const float gains[2]) {
  Update& u = pending(slot);
  u.flags |= 3u;
  u.pz[0] = p.real();
  u.pz[1] = p.imag();
  u.pz[2] = u.pz[3] = 0.0f;
  u.gain[0] = gains[0];
  u.gain[1] = channels_ == 2 ? gains[1] : 0.0f;
  set_input(slot, kNoStream, {0, 0});
}

void GpuFilterbank::set_pole(uint32_t slot, std::complex<float> p) {
  Update& u = pending(slot);
  u.flags |= 4u;
  u.pz[0] = p.real();
  u.pz[1] = p.imag();
}

void GpuFilterbank::set_input(uint32_t slot, uint32_t stream, std::complex<float> gain) {
  if (stream != kNoStream && stream >= max_streams_) {
    throw std::out_of_range("filterbank input stream " + std::to_string(stream) +
                            " exceeds max_streams " + std::to_string(max_streams_));
  }
  Update& u = pending(slot);
  u.flags |= 8u;
  u.stream = stream;
  u.input[0] = stream == kNoStream ? 0.0f : gain.real();
  u.input[1] = stream == kNoStream ? 0.0f : gain.imag();
  driven_ += (stream != kNoStream) - (stream_[slot] != kNoStream);
  stream_[slot] = stream;
}

void GpuFilterbank::set_gains(uint32_t slot, const float gains[2]) {
  Update& u = pending(slot);
  // A mode started since the last call has no sound to click: its gains apply at once.
  if (gain_ramp_ == 0 || (u.flags & 3u)) {
    u.flags |= kGains;
  } else {
    u.flags |= kRampTo;
    ramp_until_ = std::max<uint64_t>(ramp_until_, processed_ + gain_ramp_);
  }
  u.gain[0] = gains[0];
  u.gain[1] = channels_ == 2 ? gains[1] : 0.0f;
}

void GpuFilterbank::set_high_water(uint32_t slots) {
  high_water_ = std::min(slots, capacity_);
}

void GpuFilterbank::record_updates() {
  if (!update_count_) return;
  const uint32_t push[2] = {update_count_, gain_ramp_};
  seq_->dispatch(*apply_[cur_], div_up(update_count_, 64), push, sizeof(push));
  seq_->barrier();
}

void GpuFilterbank::clear_updates() {
  auto* list = static_cast<Update*>(updates_[cur_]->data());
  for (uint32_t i = 0; i < update_count_; ++i) pending_index_[list[i].slot] = kNone;
  update_count_ = 0;
  cur_ ^= 1u;  // the next updates go to the list the device is not reading
}

void GpuFilterbank::ramps_at_once(uint32_t from_slot) {
  auto* list = static_cast<Update*>(updates_[cur_]->data());
  for (uint32_t i = 0; i < update_count_; ++i)
    if ((list[i].flags & kRampTo) && list[i].slot >= from_slot)
      list[i].flags = (list[i].flags & ~kRampTo) | kGains;
}

void GpuFilterbank::flush_updates(bool at_once) {
  if (at_once) ramps_at_once(0);  // an overflowing batch: the ramp would outlive its updates
  collect();
  seq_->begin();
  record_updates();
  seq_->run();
  clear_updates();
}

std::complex<float> GpuFilterbank::state(uint32_t slot) {
  if (slot >= capacity_) throw std::out_of_range("filterbank slot out of range");
  collect();
  if (update_count_) flush_updates();
  float m[4];
  modes_->download(m, sizeof(m), uint64_t{slot} * 16);
  return {m[2], m[3]};
}

void GpuFilterbank::process(std::span<const Excitation> excitations, uint32_t frames, float* out,
                            const DriveInput& input) {
  if (frames > max_frames_) throw std::invalid_argument("process: frames exceeds max_frames()");
  collect();  // the host may write the buffers the block in flight reads only after this
  if (input.streams > max_streams_) {
    throw std::invalid_argument("process: more input streams than max_streams()");
  }
  if (input.streams && !input.samples && !stage_) {
    throw std::invalid_argument("process: input streams without samples or a device stage");
  }
  const bool driven = driven_ > 0 && input.streams > 0;
  if (driven) {  // rows past input.streams would hold stale samples
    for (uint32_t s = 0; s < high_water_; ++s) {
      if (stream_[s] != kNone && stream_[s] >= input.streams) {
        throw std::out_of_range("process: slot " + std::to_string(s) + " reads input stream " +
                                std::to_string(stream_[s]) + " of " +
                                std::to_string(input.streams));
      }
    }
  }
  if (input.device_rows > 0 && (!stage_ || input.device_rows > input.streams)) {
    throw std::invalid_argument("process: device rows without a device stage");
  }
  if (driven && input.samples) {
    const std::size_t skip = std::size_t{input.device_rows} * frames;
    std::memcpy(static_cast<float*>(inputs_->data()) + skip, input.samples + skip,
                sizeof(float) * (std::size_t{input.streams} * frames - skip));
  }
  if (excitations.size() > max_excitations_) {
    throw std::invalid_argument("process: more excitations than max_excitations()");
  }
  if (frames == 0) return;
  const uint32_t ne = stage_excitations(excitations, frames);
  const uint32_t groups = div_up(high_water_, local_ * mpi_);
  const uint32_t count = frames * channels_;
  record_block(frames, ne, groups, driven, driven && (!input.samples || input.device_rows > 0));
  processed_ += frames;
  if (!pipelined_) {
    seq_->run();
    timing_.gpu_ms = seq_->elapsed_ns(0, 2) * 1e-6;
    timing_.kernel_ms = groups ? seq_->elapsed_ns(0, 1) * 1e-6 : 0.0;
    std::memcpy(out, result_->data(), sizeof(float) * count);
    clear_updates();
    return;
  }
  // Pipelined: the device runs this block while the caller goes on; the caller gets the oldest
  // samples, which the FIFO always holds (it starts with max_frames of silence).
  seq_->submit();
  clear_updates();
  in_flight_ = true;
  flight_frames_ = frames;
  flight_groups_ = groups;
  for (uint32_t i = 0; i < count; ++i) out[i] = fifo_[(fifo_head_ + i) % fifo_.size()];
  fifo_head_ = (fifo_head_ + count) % fifo_.size();
  fifo_size_ -= count;
}

// The shader walks each invocation's excitations in offset order: map slot -> (invocation, j)
// as filterbank.comp lays modes out, and sort by (invocation, offset).
uint32_t GpuFilterbank::stage_excitations(std::span<const Excitation> excitations,
                                          uint32_t frames) {
  auto* exc = static_cast<Excitation*>(excitations_->data());
  const uint32_t ne = static_cast<uint32_t>(excitations.size());
  const uint32_t per_group = local_ * mpi_;
  for (uint32_t k = 0; k < ne; ++k) {
    const Excitation& e = excitations[k];
    if (e.slot >= capacity_ || e.offset >= frames) {
      throw std::out_of_range("process: excitation slot or offset out of range");
    }
    const uint32_t within = e.slot % per_group;
    const uint32_t invocation = e.slot / per_group * local_ + within % local_;
    exc[k] = Excitation{invocation, e.offset | (within / local_) << 16, e.re, e.im};
  }
  std::sort(exc, exc + ne, [](const Excitation& a, const Excitation& b) {
    return a.slot != b.slot ? a.slot < b.slot : (a.offset & 0xffffu) < (b.offset & 0xffffu);
  });
  return ne;
}

// Records one block: queued updates, the device input stage, the filterbank kernel and the
// tree reduction into result_, between timestamps 0, 1 (kernel done) and 2.
void GpuFilterbank::record_block(uint32_t frames, uint32_t ne, uint32_t groups, bool driven,
                                 bool from_stage) {
  const uint32_t group_modes = local_ * mpi_;
  const uint32_t count = frames * channels_;
  // Slots past the processed range take their gains at once: no dispatch would commit a ramp.
  ramps_at_once(groups * group_modes);
  const bool ramp = processed_ < ramp_until_ && groups > 0;
  seq_->begin();
  seq_->timestamp(0);
  record_updates();
  if (from_stage) {
    stage_->record(*seq_, frames);
    seq_->barrier();
  }
  if (groups == 0) {
    seq_->fill_zero(*result_);
    seq_->barrier();
  } else {
    const FilterbankPush fp{groups * group_modes, frames, ne, gain_ramp_};
    seq_->dispatch(*filterbank_[driven][ramp], groups, &fp, sizeof(fp));
    seq_->barrier();
    seq_->timestamp(1);
    // Tree reduction of the partial rows: rows -> ceil(rows/64) -> ... -> result.
    uint32_t rows = groups * rows_per_group_;
    uint32_t src = 0, dst = rows * count;
    while (rows > kReduceChunk) {
      const uint32_t next_rows = div_up(rows, kReduceChunk);
      const ReducePush rp{src, dst, rows, count, kReduceChunk, 0};
      seq_->dispatch(*reduce_, div_up(uint64_t{next_rows} * count, 64), &rp, sizeof(rp));
      seq_->barrier();
      rows = next_rows;
      std::swap(src, dst);  // ping-pong between the partials region and the one after it
    }
    const ReducePush rp{src, 0, rows, count, kReduceChunk, 1};
    seq_->dispatch(*reduce_, div_up(count, 64), &rp, sizeof(rp));
    seq_->barrier();
  }
  seq_->timestamp(2);
}

}  // namespace chladni::runtime
