#pragma once
// The CPU reference filterbank: structure-of-arrays state, SIMD across modes (AVX-512F, AVX2+FMA
// or scalar, chosen at run time), ranges of modes spread over a persistent thread pool.
#include <memory>
#include <vector>

#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/thread_pool.hpp"

namespace chladni::runtime {

namespace cpu {
struct KernelArgs;
}

enum class CpuIsa { Auto, Scalar, Avx2, Avx512 };

struct CpuFilterbankOptions {
  uint32_t capacity = 1u << 20;
  int channels = 1;
  int threads = 0;  ///< 0: all hardware threads
  CpuIsa isa = CpuIsa::Auto;
  uint32_t max_frames = 4096;
  uint32_t max_excitations = 1u << 20;
  uint32_t gain_ramp = 256;  ///< samples over which gain changes ramp (0: at once)
};

class CpuFilterbank final : public Filterbank {
 public:
  explicit CpuFilterbank(const CpuFilterbankOptions& options = {});
  ~CpuFilterbank() override;

  /// Whether this processor can run `isa`.
  static bool supports(CpuIsa isa);

  std::string name() const override;
  uint32_t capacity() const override { return capacity_; }
  int channels() const override { return channels_; }
  uint32_t max_frames() const override { return max_frames_; }
  uint32_t max_excitations() const override { return max_excitations_; }
  uint32_t max_streams() const override { return kNoStream - 1; }
  int threads() const { return pool_->threads(); }

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

 private:
  struct Task;
  static void run_task(void* self, int index);

  uint32_t capacity_, padded_, high_water_;
  int channels_;
  uint32_t max_frames_, max_excitations_;
  int isa_;
  void (*kernel_)(const cpu::KernelArgs&);
  struct AlignedFree {
    void operator()(float* p) const;
  };
  std::unique_ptr<float[], AlignedFree> pr_, pi_, zr_, zi_, g0_, g1_, ar_, ai_, t0_, t1_, el_;
  // Gain ramps: a ramping slot goes from g0_/g1_ to its targets t0_/t1_ over gain_ramp_ samples,
  // el_ of them elapsed; elsewhere the targets equal the gains. touched_ lists the slots that
  // ramp or were started in this call (their gains apply at once).
  enum : uint8_t { kIdle = 0, kRamping = 1, kStarted = 2 };
  uint32_t gain_ramp_;
  std::vector<uint8_t> touch_;
  std::vector<uint32_t> touched_;
  std::vector<uint32_t> src_;  // input stream per slot, kNoStream when undriven
  uint32_t driven_ = 0;        // slots with a stream
  DriveInput input_;
  std::vector<Excitation> sorted_;
  std::vector<float> task_out_, task_lanes_;
  std::vector<uint32_t> task_range_;  // per task: begin, end, exc_begin, exc_end
  std::unique_ptr<ThreadPool> pool_;
  uint32_t frames_ = 0;
  bool ramping_ = false;
};

}  // namespace chladni::runtime
