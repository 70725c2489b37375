#pragma once
// Voices over a filterbank. A voice is a set of modes with a gain each and a per-channel pan.
// Modes take filterbank slots only while they ring: an excitation makes them resident, and a mode
// whose envelope has fallen `retire_db` below its peak is retired and its slot reused. When the
// mode budget is full, the least audible resident modes are stolen.
//
// Threading: prepare_voice() and start_voice(span) allocate and belong on a control thread;
// start_voice(VoiceData&), excite(), set_*(), stop_voice() and render() do not allocate, lock or
// block (beyond the filterbank's own work).
#include <complex>
#include <cstdint>
#include <span>
#include <vector>

#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/modal/contact_forces.hpp"

namespace chladni::runtime {

struct ModeSpec {
  double omega_d = 0;  ///< damped angular frequency (rad/s)
  double decay = 0;    ///< 1/s
  float gain = 1;      ///< output per unit of modal state Im(z)
};

struct SynthOptions {
  double sample_rate = 48000;
  uint32_t max_modes = 0;   ///< mode budget, leased from the filterbank; 0: every unleased slot
  double retire_db = -100;  ///< retire a mode this far below its peak envelope
  uint32_t max_voices = 1024;
  /// Modes (summed over impacts) and impacts that strike() drives through their contact at
  /// once; past them an impact's modes start at the state they have after the contact.
  uint32_t max_contact_modes = 1u << 15;
  uint32_t max_contacts = 256;
};

struct SynthStats {
  uint64_t retired = 0;            ///< modes retired by envelope
  uint64_t stolen = 0;             ///< modes stolen to make room
  uint64_t skipped = 0;            ///< excitations too weak to make a mode resident
  uint64_t contacts_undriven = 0;  ///< strikes past max_contacts / max_contact_modes
};

class Synth {
 public:
  using VoiceId = int32_t;
  Synth(Filterbank& filterbank, const SynthOptions& options);
  /// Clears the synth's slots and gives its lease back (the filterbank must outlive it).
  ~Synth();
  Synth(const Synth&) = delete;
  Synth& operator=(const Synth&) = delete;

  /// A voice's storage: its modes, their slots and the scratch of its strikes.
  struct VoiceData {
    std::vector<ModeSpec> modes;
    std::vector<int32_t> slot;    // -1 when not resident
    std::vector<uint8_t> kicked;  // per mode of the last kick(): whether it reached the filterbank
    std::vector<std::complex<float>> strike_amp;
  };
  /// The storage of a voice of `modes`, made off the audio thread. Throws InputError on
  /// non-finite or negative values.
  static VoiceData prepare_voice(std::span<const ModeSpec> modes);
  /// Registers a prepared voice (no slot is taken yet) without allocating: `data` receives the
  /// storage the voice's place held before, for the caller to free off the audio thread. -1 when
  /// max_voices voices are alive.
  VoiceId start_voice(VoiceData& data) noexcept;
  /// prepare_voice() and start_voice(data) in one (control thread). Throws when no voice is free.
  VoiceId start_voice(std::span<const ModeSpec> modes);
  /// Per-channel gains of the whole voice (right ignored in mono). Default 1, 1.
  void set_pan(VoiceId voice, float left, float right);
  /// New per-mode gains; resident modes change at the next render().
  void set_mode_gains(VoiceId voice, std::span<const float> gains);
  /// Adds amplitude[i] to mode i's state at sample `offset` of the next render().
  void excite(VoiceId voice, std::span<const std::complex<float>> amplitude, uint32_t offset);
  /// An impact: `coupling[i]` is the state kick of mode i for the whole impulse, delivered by a
  /// half-sine force over `contact` seconds (0: an ideal impulse) from fractional sample `start`
  /// of the next render (-1 < start, ceil(start) < max_frames()). The modes build up under the
  /// force as it acts and ring on from the state the contact leaves (contact_forces.hpp).
  void strike(VoiceId voice, std::span<const std::complex<float>> coupling, double start,
              double contact);
  /// Silences and forgets the voice; its slots are freed at once.
  void stop_voice(VoiceId voice);

  /// Renders `frames` (<= max_frames()) interleaved frames into `out`; `drive` feeds the
  /// filterbank's driven slots (a ShakerBank's prepare()).
  void render(uint32_t frames, float* out, const DriveInput& drive = {});

  uint32_t max_frames() const { return fb_.max_frames(); }
  uint32_t pending_excitations() const { return static_cast<uint32_t>(pending_count_); }
  uint32_t excitation_capacity() const { return fb_.max_excitations(); }
  uint32_t active_modes() const { return used_; }
  uint32_t high_water() const { return high_water_; }
  uint64_t time() const { return now_; }  ///< samples rendered so far
  const SynthStats& stats() const { return stats_; }
  int slot_of(VoiceId voice, std::size_t mode) const;

 private:
  struct Voice : VoiceData {
    bool alive = false;
    float pan[2] = {1, 1};
  };
  void kick(Voice& voice, VoiceId id, std::span<const std::complex<float>> amplitude,
            uint32_t offset);
  static void contact_gains(const void* self, int32_t voice, uint32_t mode, float gains[2]);
  uint32_t allocate_slot();
  void free_slot(uint32_t slot);
  void steal(uint32_t needed);
  void apply_gains(uint32_t slot);
  void drop_pending(uint32_t slot);
  double envelope(uint32_t slot, int64_t t) const;  ///< bound on |z| at sample t
  Voice& voice(VoiceId id);
  void render_forces(uint32_t frames, float* out);

  Filterbank& fb_;
  SynthOptions opt_;
  double threshold_;  // amplitude ratio of retire_db
  uint32_t budget_;
  SlotLease lease_;  // the filterbank slots [lease_.begin, +budget_) are this synth's
  std::vector<Voice> voices_;
  // Per slot: owner, envelope bound |z| <= env at time env_time, peak, decay per sample, retire
  // time (samples).
  std::vector<int32_t> slot_voice_;
  std::vector<uint32_t> slot_mode_;
  std::vector<float> env_, peak_, rate_;
  std::vector<int64_t> env_time_, retire_at_;
  std::vector<uint32_t> free_heap_;   // min-heap keeps resident slots low (fewer to process)
  std::vector<uint32_t> group_used_;  // resident slots per group of 256
  std::vector<std::pair<float, uint32_t>> steal_scratch_;
  std::vector<Excitation> pending_;
  ContactForces forces_;
  // The contact forces are added on the host: behind a filterbank whose output lags (a pipelined
  // device), they lag as much, through this ring of (latency + max_frames) frames.
  std::vector<float> force_block_, force_delay_;
  std::size_t delay_head_ = 0;
  std::size_t pending_count_ = 0;
  uint32_t used_ = 0, high_water_ = 0, scan_cursor_ = 0;
  uint64_t now_ = 0;
  SynthStats stats_;
};

}  // namespace chladni::runtime
