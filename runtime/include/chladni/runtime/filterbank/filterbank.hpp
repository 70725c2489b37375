#pragma once
// One interface, two implementations (CpuFilterbank, GpuFilterbank). A filterbank holds
// `capacity()` mode slots; each is a complex one-pole resonator z <- p z + e (DESIGN.md) with one
// gain per output channel. Slot changes are queued and take effect at the start of the next
// process(); process() advances all slots [0, high_water) by `frames` samples and writes the
// interleaved output. Implementations agree sample by sample (tests hold them together).
#include <complex>
#include <cstdint>
#include <span>
#include <string>

namespace chladni::runtime {

class GpuFilterbank;

/// An impulse added to a slot's state right after the pole multiplication at sample `offset`
/// of the next process() call.
struct Excitation {
  uint32_t slot;
  uint32_t offset;
  float re;
  float im;
};

/// Dense per-sample input for driven slots (stochastic excitation): `streams` rows of
/// `frames` samples each, row-major. A slot driven by stream k with gain a advances as
/// z[n] = p z[n-1] + a x_k[n] (+ any impulse at n).
struct DriveInput {
  const float* samples = nullptr;  ///< streams * frames, or nullptr (see GpuFilterbank)
  uint32_t streams = 0;
  /// Rows [0, device_rows) are written by a GpuFilterbank's device input stage, the rest come
  /// from `samples` (0: all from `samples`, or all from the stage where `samples` is null).
  uint32_t device_rows = 0;
};

/// Stream index of an undriven slot.
constexpr uint32_t kNoStream = 0xffffffffu;

/// Consecutive slots [begin, end) that one user of a filterbank owns (Filterbank::lease()).
struct SlotLease {
  uint32_t begin = 0, end = 0;
  int id = -1;
  uint32_t size() const { return end - begin; }
};

struct FilterbankTiming {
  double gpu_ms = 0;     ///< device time of the last process() (0 when unknown)
  double kernel_ms = 0;  ///< of which the filterbank kernel (the rest: updates, reduction)
};

class Filterbank {
 public:
  virtual ~Filterbank() = default;

  virtual std::string name() const = 0;  ///< "cpu (avx2, 2 threads)", "gpu (llvmpipe ...)"
  virtual uint32_t capacity() const = 0;
  virtual int channels() const = 0;
  /// Largest `frames` one process() call accepts.
  virtual uint32_t max_frames() const = 0;
  /// Largest number of excitations one process() call accepts.
  virtual uint32_t max_excitations() const = 0;

  /// Largest number of input streams one process() call accepts.
  virtual uint32_t max_streams() const = 0;

  /// Starts a mode in `slot`: pole p, zero state, channel gains (gains[1] ignored in mono), and
  /// no input stream.
  virtual void set_mode(uint32_t slot, std::complex<float> pole, const float gains[2]) = 0;
  /// Changes a slot's pole, keeping its state (retuning a ringing resonance).
  virtual void set_pole(uint32_t slot, std::complex<float> pole) = 0;
  /// Drives a slot from input stream `stream` (< max_streams(), or kNoStream) with `gain`.
  virtual void set_input(uint32_t slot, uint32_t stream, std::complex<float> gain) = 0;
  /// Changes a slot's gains, keeping its state. The change ramps linearly over gain_ramp()
  /// samples from the start of the next process() call, across calls of any size, so that a
  /// ringing mode does not click; a change in mid-ramp starts from where the ramp has got to. It
  /// takes effect at once for a slot that set_mode() started since the last call.
  virtual void set_gains(uint32_t slot, const float gains[2]) = 0;
  /// Samples over which set_gains() ramps (0: at once).
  virtual uint32_t gain_ramp() const = 0;
  /// Silences a slot (pole, state and gains to zero).
  void clear_mode(uint32_t slot) {
    const float zero[2] = {0, 0};
    set_mode(slot, {0, 0}, zero);
  }
  /// Slots at or above this are known to be clear and are skipped by process().
  virtual void set_high_water(uint32_t slots) = 0;

  /// Users that share a filterbank (a Synth's voices, a ShakerBank's particles) each lease a
  /// range of slots: the next `count` after those leased so far. InputError when they do not
  /// fit or kMaxLeases are out. Control thread.
  SlotLease lease(uint32_t count);
  /// Gives a lease back (its user is done; its slots should be clear). Slots return to the pool
  /// once every lease above them is released too.
  void release(const SlotLease& lease);
  /// Slots not leased yet.
  uint32_t unleased() const { return capacity() - leased_end_; }
  /// A lease's user says its first `used` slots may sound; process() then covers every lease's
  /// used part (set_high_water). Allocates nothing.
  void set_used(const SlotLease& lease, uint32_t used);
  static constexpr int kMaxLeases = 8;

  /// Advances by `frames` samples; `out` receives frames * channels() interleaved samples.
  /// Excitations may come in any order; their offsets must be < frames.
  void process(std::span<const Excitation> excitations, uint32_t frames, float* out) {
    process(excitations, frames, out, DriveInput{});
  }
  /// Likewise, with the driven slots reading `input` (a slot's stream must be < input.streams).
  virtual void process(std::span<const Excitation> excitations, uint32_t frames, float* out,
                       const DriveInput& input) = 0;

  /// Reads back one slot's state (for tests and diagnostics; may be slow).
  virtual std::complex<float> state(uint32_t slot) = 0;
  virtual FilterbankTiming last_timing() const { return {}; }
  /// Samples by which process()'s output lags its input (a pipelined device: its block size).
  virtual uint32_t latency() const { return 0; }
  /// The Vulkan filterbank this is (null for the CPU one): stages that feed its inputs on the
  /// device (a GPU particle excitation) need it.
  virtual GpuFilterbank* device() { return nullptr; }

 private:
  uint32_t leased_end_ = 0;
  int leases_ = 0;
  uint32_t used_end_[kMaxLeases] = {};
  uint32_t begin_[kMaxLeases] = {};
  bool released_[kMaxLeases] = {};
};

/// The pole of a mode with damped angular frequency omega_d (rad/s) and decay rate d (1/s).
std::complex<float> pole(double omega_d, double decay, double sample_rate);

}  // namespace chladni::runtime
