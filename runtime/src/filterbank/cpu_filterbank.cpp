#include "chladni/runtime/filterbank/cpu_filterbank.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>
#include <thread>

#include "denormals.hpp"
#include "filterbank/cpu_kernels.hpp"

namespace chladni::runtime {
namespace {

cpu::Isa to_internal(CpuIsa isa) {
  switch (isa) {
    case CpuIsa::Scalar:
      return cpu::Isa::Scalar;
    case CpuIsa::Avx2:
      return cpu::Isa::Avx2;
    case CpuIsa::Avx512:
      return cpu::Isa::Avx512;
    default:
      return cpu::best_isa();
  }
}

float* aligned_floats(std::size_t n) {
  void* p = std::aligned_alloc(64, ((n * sizeof(float) + 63) / 64) * 64);
  if (!p) throw std::bad_alloc();
  std::memset(p, 0, n * sizeof(float));
  return static_cast<float*>(p);
}

// Lane scratch per task: frames * channels * 16 floats (the widest SIMD).
constexpr std::size_t kMaxLanes = 16;

}  // namespace

void CpuFilterbank::AlignedFree::operator()(float* p) const {
  std::free(p);
}

bool CpuFilterbank::supports(CpuIsa isa) {
  return isa == CpuIsa::Auto || cpu::isa_supported(to_internal(isa));
}

CpuFilterbank::CpuFilterbank(const CpuFilterbankOptions& o)
    : capacity_(o.capacity),
      padded_((o.capacity + cpu::kGroup - 1) / cpu::kGroup * cpu::kGroup),
      high_water_(o.capacity),
      channels_(o.channels),
      max_frames_(o.max_frames),
      max_excitations_(o.max_excitations),
      gain_ramp_(o.gain_ramp) {
  if (o.capacity == 0) throw std::invalid_argument("filterbank capacity must be > 0");
  if (o.channels != 1 && o.channels != 2) throw std::invalid_argument("channels must be 1 or 2");
  if (o.max_frames == 0) throw std::invalid_argument("max_frames must be > 0");
  const cpu::Isa isa = to_internal(o.isa);
  if (!cpu::isa_supported(isa)) {
    throw std::invalid_argument(std::string("this processor cannot run the ") + cpu::isa_name(isa) +
                                " filterbank");
  }
  isa_ = static_cast<int>(isa);
  kernel_ = cpu::kernel_for(isa);
  pr_.reset(aligned_floats(padded_));
  pi_.reset(aligned_floats(padded_));
  zr_.reset(aligned_floats(padded_));
  zi_.reset(aligned_floats(padded_));
  g0_.reset(aligned_floats(padded_));
  g1_.reset(aligned_floats(padded_));
  ar_.reset(aligned_floats(padded_));
  ai_.reset(aligned_floats(padded_));
  t0_.reset(aligned_floats(padded_));
  t1_.reset(aligned_floats(padded_));
  el_.reset(aligned_floats(padded_));
  touch_.assign(padded_, kIdle);
  touched_.reserve(padded_);
  src_.assign(padded_, kNoStream);
  const int threads = o.threads > 0
                          ? o.threads
                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  pool_ = std::make_unique<ThreadPool>(threads);
  sorted_.resize(max_excitations_);
  task_out_.resize(static_cast<std::size_t>(threads) * max_frames_ * channels_);
  task_lanes_.resize(static_cast<std::size_t>(threads) * max_frames_ * channels_ * kMaxLanes + 16);
  task_range_.resize(static_cast<std::size_t>(threads) * 4);
}

CpuFilterbank::~CpuFilterbank() = default;

std::string CpuFilterbank::name() const {
  return std::string("cpu (") + cpu::isa_name(static_cast<cpu::Isa>(isa_)) + ", " +
         std::to_string(pool_->threads()) + (pool_->threads() == 1 ? " thread)" : " threads)");
}

void CpuFilterbank::set_mode(uint32_t slot, std::complex<float> p, const float gains[2]) {
  if (slot >= capacity_) throw std::out_of_range("filterbank slot out of range");
  pr_[slot] = p.real();
  pi_[slot] = p.imag();
  zr_[slot] = zi_[slot] = 0.0f;
  t0_[slot] = g0_[slot] = gains[0];
  t1_[slot] = g1_[slot] = channels_ == 2 ? gains[1] : 0.0f;
  if (touch_[slot] == kIdle) touched_.push_back(slot);
  touch_[slot] = kStarted;
  set_input(slot, kNoStream, {0, 0});
}

void CpuFilterbank::set_pole(uint32_t slot, std::complex<float> p) {
  if (slot >= capacity_) throw std::out_of_range("filterbank slot out of range");
  pr_[slot] = p.real();
  pi_[slot] = p.imag();
}

void CpuFilterbank::set_input(uint32_t slot, uint32_t stream, std::complex<float> gain) {
  if (slot >= capacity_) throw std::out_of_range("filterbank slot out of range");
  driven_ += (stream != kNoStream) - (src_[slot] != kNoStream);
  src_[slot] = stream;
  ar_[slot] = stream == kNoStream ? 0.0f : gain.real();
  ai_[slot] = stream == kNoStream ? 0.0f : gain.imag();
}

void CpuFilterbank::set_gains(uint32_t slot, const float gains[2]) {
  if (slot >= capacity_) throw std::out_of_range("filterbank slot out of range");
  const float t0 = gains[0], t1 = channels_ == 2 ? gains[1] : 0.0f;
  if (gain_ramp_ == 0 || touch_[slot] == kStarted) {
    g0_[slot] = t0_[slot] = t0;
    g1_[slot] = t1_[slot] = t1;
    return;
  }
  if (touch_[slot] == kRamping) {  // a new ramp starts from where this one has got to
    const float w = std::min(1.0f, el_[slot] / static_cast<float>(gain_ramp_));
    g0_[slot] += w * (t0_[slot] - g0_[slot]);
    g1_[slot] += w * (t1_[slot] - g1_[slot]);
  } else {
    touched_.push_back(slot);
    touch_[slot] = kRamping;
  }
  t0_[slot] = t0;
  t1_[slot] = t1;
  el_[slot] = 0.0f;
}

void CpuFilterbank::set_high_water(uint32_t slots) {
  high_water_ = std::min(slots, capacity_);
}

std::complex<float> CpuFilterbank::state(uint32_t slot) {
  if (slot >= capacity_) throw std::out_of_range("filterbank slot out of range");
  return {zr_[slot], zi_[slot]};
}

void CpuFilterbank::run_task(void* self_ptr, int t) {
  auto* self = static_cast<CpuFilterbank*>(self_ptr);
  const uint32_t* r = &self->task_range_[static_cast<std::size_t>(t) * 4];
  cpu::KernelArgs a{};
  a.pr = self->pr_.get();
  a.pi = self->pi_.get();
  a.zr = self->zr_.get();
  a.zi = self->zi_.get();
  a.g0 = self->g0_.get();
  a.g1 = self->g1_.get();
  a.t0 = self->t0_.get();
  a.t1 = self->t1_.get();
  a.el = self->ramping_ ? self->el_.get() : nullptr;
  a.inv_ramp = self->gain_ramp_ ? 1.0f / static_cast<float>(self->gain_ramp_) : 0.0f;
  a.begin = r[0];
  a.end = r[1];
  a.exc = self->sorted_.data() + r[2];
  a.exc_count = r[3] - r[2];
  a.frames = self->frames_;
  a.channels = self->channels_;
  a.src = self->src_.data();
  a.ar = self->ar_.get();
  a.ai = self->ai_.get();
  a.in = self->driven_ ? self->input_.samples : nullptr;
  a.out =
      self->task_out_.data() + static_cast<std::size_t>(t) * self->max_frames_ * self->channels_;
  // 64-byte aligned lane scratch.
  float* lanes = self->task_lanes_.data() +
                 static_cast<std::size_t>(t) * self->max_frames_ * self->channels_ * kMaxLanes;
  a.lanes = reinterpret_cast<float*>((reinterpret_cast<uintptr_t>(lanes) + 63) & ~uintptr_t{63});
  if (a.begin < a.end) {
    self->kernel_(a);
  } else {
    std::memset(a.out, 0, sizeof(float) * a.frames * a.channels);
  }
}

void CpuFilterbank::process(std::span<const Excitation> excitations, uint32_t frames, float* out,
                            const DriveInput& input) {
  if (frames > max_frames_) throw std::invalid_argument("process: frames exceeds max_frames()");
  if (driven_ && input.streams) {
    if (!input.samples) throw std::invalid_argument("process: input streams without samples");
    // A driven slot must name a row that exists: checked here, not in the hot loop.
    for (uint32_t s = 0; s < high_water_; ++s) {
      if (src_[s] != kNoStream && src_[s] >= input.streams) {
        throw std::out_of_range("process: slot " + std::to_string(s) + " reads input stream " +
                                std::to_string(src_[s]) + " of " + std::to_string(input.streams));
      }
    }
  }
  input_ = input.streams ? input : DriveInput{};
  if (excitations.size() > max_excitations_) {
    throw std::invalid_argument("process: more excitations than max_excitations()");
  }
  if (frames == 0) return;
  ScopedFlushDenormals ftz;
  // Order excitations as the kernel walks them: by group of 64 slots, then sample, then slot.
  const std::size_t ne = excitations.size();
  for (std::size_t k = 0; k < ne; ++k) {
    const Excitation& e = excitations[k];
    if (e.slot >= capacity_ || e.offset >= frames) {
      throw std::out_of_range("process: excitation slot or offset out of range");
    }
    sorted_[k] = e;
  }
  std::sort(sorted_.begin(), sorted_.begin() + ne, [](const Excitation& a, const Excitation& b) {
    const uint32_t ga = a.slot / cpu::kGroup, gb = b.slot / cpu::kGroup;
    if (ga != gb) return ga < gb;
    if (a.offset != b.offset) return a.offset < b.offset;
    return a.slot < b.slot;
  });
  frames_ = frames;
  ramping_ = false;
  for (uint32_t s : touched_) ramping_ = ramping_ || touch_[s] == kRamping;
  const uint32_t active = (high_water_ + cpu::kGroup - 1) / cpu::kGroup * cpu::kGroup;
  const int tasks = pool_->threads();
  const uint32_t groups = active / cpu::kGroup;
  for (int t = 0; t < tasks; ++t) {
    uint32_t* r = &task_range_[static_cast<std::size_t>(t) * 4];
    r[0] = static_cast<uint32_t>(uint64_t{groups} * t / tasks) * cpu::kGroup;
    r[1] = static_cast<uint32_t>(uint64_t{groups} * (t + 1) / tasks) * cpu::kGroup;
    auto by_slot = [](const Excitation& e, uint32_t s) { return e.slot < s; };
    r[2] = static_cast<uint32_t>(
        std::lower_bound(sorted_.begin(), sorted_.begin() + ne, r[0], by_slot) - sorted_.begin());
    r[3] = static_cast<uint32_t>(
        std::lower_bound(sorted_.begin(), sorted_.begin() + ne, r[1], by_slot) - sorted_.begin());
  }
  pool_->run(&CpuFilterbank::run_task, this, tasks);
  // Ramps that are over leave their targets as the gains; the others go on next call.
  std::size_t kept = 0;
  for (uint32_t s : touched_) {
    if (touch_[s] == kRamping && el_[s] + static_cast<float>(frames) < gain_ramp_) {
      el_[s] += static_cast<float>(frames);
      touched_[kept++] = s;
      continue;
    }
    g0_[s] = t0_[s];
    g1_[s] = t1_[s];
    touch_[s] = kIdle;
  }
  touched_.resize(kept);
  const std::size_t count = static_cast<std::size_t>(frames) * channels_;
  std::memcpy(out, task_out_.data(), count * sizeof(float));
  for (int t = 1; t < tasks; ++t) {
    const float* src = task_out_.data() + static_cast<std::size_t>(t) * max_frames_ * channels_;
    for (std::size_t i = 0; i < count; ++i) out[i] += src[i];
  }
}

}  // namespace chladni::runtime
