#pragma once
// PhISEM voices on a filterbank (phisem.hpp for the model). Each voice is one input stream, its
// stochastic excitation, driving its resonances, which sit in consecutive filterbank slots:
//  - an instrument's few resonances (maraca, tambourine, ...), where STK's two-pole resonance
//    y = g x - a1 y1 - a2 y2 is exactly the slot Im(z), z <- p z + (g e^{i theta} / sin theta) x;
//  - or the modes of a soundbank ("gravel poured into a steel bowl"): each shake moves the contact
//    to a random surface point of the object, and the excitation is an impulse train in N*s
//    along the normal there, q_i kicked by (v_i . n) / omega_d per N*s (DESIGN.md).
// The excitation is made on the CPU (phisem_generate) or by kernels/phisem.comp inside the GPU
// filterbank's submission; both give the same samples for the same seed.
//
// Threading: add_voice(const ShakerVoice&) and prepare_voice() allocate and belong on a control
// thread; add_voice(PreparedVoice&, index) (with reserve_all), remove_voice(), shake(),
// prepare(), finish() and render() neither allocate nor lock.
#include <complex>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "chladni/core/audio_file.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/filterbank/slot_runs.hpp"
#include "chladni/runtime/phisem/phisem.hpp"
#include "chladni/runtime/thread_pool.hpp"

namespace chladni::runtime {

struct ObjectModes;

struct ShakerResonance {
  double omega_d = 0;               ///< damped angular frequency (rad/s)
  double decay = 0;                 ///< 1/s
  std::complex<float> input{1, 0};  ///< state kick per unit of excitation
  float gain = 1;                   ///< output per unit of Im(z)
  double vary = 0;   ///< relative random retuning after blocks with collisions (0: fixed)
  double sweep = 1;  ///< frequency factor per second of a retuned resonance
};

struct ShakerVoice {
  std::string name;
  PhisemParams excitation;
  std::vector<ShakerResonance> resonances;
  /// Drive gains per contact point and resonance (object voices); empty: each resonance's input.
  std::vector<std::vector<std::complex<float>>> contacts;
  float pan[2] = {1, 1};
};

/// An instrument at `sample_rate`; `objects` > 0 overrides its particle count.
ShakerVoice instrument_voice(const PhisemPreset& preset, double sample_rate, double objects = 0);

/// The object's modes driven by the preset's particle process: `impulse` N*s per unit of
/// excitation, `contacts` surface points drawn from `seed` (the object needs geometry).
ShakerVoice object_voice(const PhisemPreset& preset, const ObjectModes& object, double sample_rate,
                         double impulse, std::size_t contacts, uint64_t seed, double objects = 0);

enum class ExcitationBackend { Cpu, Gpu };

struct ShakerBankOptions {
  double sample_rate = 48000;
  uint32_t slots = 0;  ///< slots leased from the filterbank for the voices; 0: every unleased one
  uint32_t max_voices = 4096;
  uint32_t max_shakes = 4096;  ///< per block
  uint64_t seed = 1;
  ExcitationBackend excitation = ExcitationBackend::Cpu;  ///< Gpu needs a GpuFilterbank
  int threads = 1;  ///< CPU excitation threads (0: all hardware threads)
  /// Reserve every voice's storage at construction, so that add_voice(PreparedVoice&) never
  /// allocates (a live scene's voices come and go while it plays).
  bool reserve_all = false;
};

class ShakerBank {
 public:
  /// Throws InputError for bad options, gpu::NoDeviceError/Error for a GPU excitation without a
  /// GpuFilterbank whose max_streams() covers max_voices.
  ShakerBank(Filterbank& filterbank, const ShakerBankOptions& options);
  ~ShakerBank();
  ShakerBank(const ShakerBank&) = delete;
  ShakerBank& operator=(const ShakerBank&) = delete;

  /// Adds a voice (silent until shaken). Throws InputError on non-finite values or when the
  /// filterbank or max_voices is full.
  int add_voice(const ShakerVoice& voice);
  /// A voice validated and built off the audio thread; add_voice(PreparedVoice&) places it.
  struct PreparedVoice;
  /// Throws InputError naming the voice on non-finite values or no resonances.
  static std::unique_ptr<PreparedVoice> prepare_voice(const ShakerVoice& voice);
  /// Places a prepared voice at `index` (a removed voice's, or voice_count()) on a run of free
  /// slots, without allocating; `prepared` receives what the index held before. False when the
  /// index is taken or beyond max_voices, or no run of slots is long enough.
  bool add_voice(PreparedVoice& prepared, uint32_t index);
  /// Silences a voice at once (fade its gains first), frees its slots for later voices and its
  /// index for add_voice(PreparedVoice&), and drops its pending shakes.
  void remove_voice(int voice) noexcept;
  bool live(int voice) const {
    return voice >= 0 && static_cast<std::size_t>(voice) < voices_.size() && voices_[voice].live;
  }
  /// Adds `amount` (0-1) of energy to a voice at sample `offset` of the next block. Returns false
  /// (and drops it) when the block's shake list is full or the input is invalid.
  bool shake(int voice, float amount, uint32_t offset);
  /// New output gains of a voice's resonances (`gains` per resonance, times the pan), keeping
  /// their states: a listener or object moved.
  void set_gains(int voice, std::span<const float> gains, float left, float right);

  /// Renders `frames` (<= the filterbank's max_frames()) through the filterbank, this bank alone.
  void render(uint32_t frames, float* out);
  /// When the filterbank is shared (render_scene's Synth): prepare() returns the input of the next
  /// process() call of `frames`, finish() follows that call.
  DriveInput prepare(uint32_t frames);
  void finish(uint32_t frames);

  uint32_t voice_count() const { return static_cast<uint32_t>(voices_.size()); }
  uint32_t slot_end() const { return slot_end_; }
  /// The voice's excitation state after the last block (collisions, energy, counter).
  PhisemState state(int voice) const;
  /// The excitation of the last block (CPU backend; for tests), voice-major rows of `frames`.
  const float* last_input() const { return input_.data(); }
  const std::string& backend_name() const { return backend_name_; }

 private:
  struct Voice {
    bool live = false;
    float pan[2] = {1, 1};
    uint32_t first_slot = 0;
    std::vector<ShakerResonance> res;
    std::vector<double> base_hz, hz;  // vary/sweep resonances: base and current tuning
    std::vector<std::vector<std::complex<float>>> contacts;
    uint32_t collisions_before = 0;
    bool varies = false;
  };
  class GpuStage;
  static void generate_task(void* self, int task);
  PhisemState& state_ref(int voice);
  uint32_t take_slots(uint32_t count) noexcept;
  void give_slots(uint32_t first, uint32_t count) noexcept;
  void retune(Voice& v, const PhisemState& st, uint32_t frames);

  Filterbank& fb_;
  ShakerBankOptions opt_;
  SlotLease lease_;
  uint32_t slot_end_ = 0;
  // Runs of slots freed by removed voices (first, count), sorted and merged.
  SlotRuns free_runs_;
  std::vector<Voice> voices_;
  std::vector<PhisemParams> params_;
  std::vector<PhisemState> states_;  // CPU backend
  std::vector<Shake> shakes_;
  std::size_t shake_count_ = 0;
  std::vector<float> input_;  // CPU backend: voices x max_frames
  std::unique_ptr<ThreadPool> pool_;
  uint32_t frames_ = 0;
  int tasks_ = 1;
  std::unique_ptr<GpuStage> gpu_;
  std::string backend_name_;
};

struct ShakerBank::PreparedVoice {
  Voice voice;
  PhisemParams params;
};

/// A shake at a time (s) for offline rendering.
struct TimedShake {
  double time = 0;
  int voice = 0;
  float amount = 0;
};

/// Shakes at `rate` per second on every voice of the bank over [0, until), `amount` each, the
/// voices' shakes staggered evenly within a period.
std::vector<TimedShake> regular_shakes(uint32_t voices, double rate, double until, float amount);

/// Renders `seconds` of the bank alone, each shake placed at its sample. `events` sorted by time.
AudioBuffer render_shaker(ShakerBank& bank, int channels, double sample_rate,
                          std::span<const TimedShake> events, double seconds, uint32_t block);

}  // namespace chladni::runtime
