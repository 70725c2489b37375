#pragma once
// Continuous contacts (sliding, rolling) on a filterbank. Each contact is one input stream, its
// force (contact_excitation.hpp), which drives the modes of the one or two bodies it touches:
// each body's modes sit in slots of their own, fed through the mode shapes at the body's contact
// point, q_i' += (v_i(x) . n_in) f dt / omega_d (the impact's coupling, DESIGN.md, per sample),
// n_in the body's inward normal there. A mode's output is its pressure from modal acceleration,
// taken as omega_d^2 q (exact while it rings freely); under a sustained force at f below the
// mode that would overstate what it radiates by (f_mode / f)^2, a rumble below every mode. So the
// stream carries the force's second derivative and each drive gain is divided by omega_d^2: the
// slot then holds q'' / omega_d^2, and its output is the modal acceleration at every frequency. Two
// bodies in contact press on each other along opposite normals, so one stream drives both with
// equal and opposite forces. The modes are linear, so these slots ring beside the bodies' impact
// voices and their sum is the body's response.
//
// The contact is given as control points (the values at a sample: normal force, slip and
// rolling speed, each body's surface point), at any rate; between them every value is
// interpolated linearly per sample, and the force fades in over `ramp` samples from the first
// point and out over `ramp` samples from end(), so nothing steps. A body's surface point changes
// its drive gains at the first block that starts past the point naming it.
//
// Contacts come and go while the bank plays: prepare() builds one off the audio thread,
// install() places it at an index on a run of free slots without allocating, and remove() fades
// it out; once its modes have rung down by 60 dB their gains ramp to zero, the slots and the
// index are freed, and retired() reports the index.
//
// Threading: the constructor, prepare() and add_contact() allocate (a control thread); install(),
// push(), end(), remove(), set_gains() and render() neither allocate nor lock.
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "chladni/runtime/contact/contact_excitation.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/filterbank/slot_runs.hpp"
#include "chladni/runtime/modal/object_modes.hpp"

namespace chladni::runtime {

struct ContactSpec {
  std::string name;  ///< for messages
  /// The bodies in contact: the first, and optionally a second (null), pressed the other way.
  /// Copied; the models they point to must outlive the bank.
  std::array<const ObjectModes*, 2> bodies{nullptr, nullptr};
  Roughness roughness;
  uint64_t seed = 1;
};

struct ContactPoint {
  uint64_t sample = 0;                   ///< absolute sample at which these values hold
  float force = 0;                       ///< normal force (N), >= 0
  float slip = 0;                        ///< slip speed (m/s), >= 0
  float rolling = 0;                     ///< rolling speed (m/s), >= 0
  std::array<uint32_t, 2> vertex{0, 0};  ///< each body's surface point (ignored without geometry)
};

struct ContactBankOptions {
  double sample_rate = 48000;
  uint32_t slots = 0;  ///< leased from the filterbank; 0: every unleased slot
  uint32_t max_contacts = 64;
  uint32_t stream_base = 0;  ///< contact k drives input stream stream_base + k
  uint32_t ramp = 256;       ///< samples of a contact's fade in and out
  uint32_t max_points = 64;  ///< control points queued per contact
};

class ContactBank {
 public:
  ContactBank(Filterbank& filterbank, const ContactBankOptions& options);
  /// Clears the bank's slots and gives its lease back.
  ~ContactBank();
  ContactBank(const ContactBank&) = delete;
  ContactBank& operator=(const ContactBank&) = delete;

  /// A contact built off the audio thread (its profile tables, queues and the bodies' modes).
  struct Prepared;
  /// Throws InputError naming the contact when its roughness is out of range, a body has no
  /// modes, or its modes exceed the bank's slots.
  std::unique_ptr<Prepared> prepare(const ContactSpec& spec) const;
  /// Places `prepared` at `index` (< max_contacts, not in use) on a run of free slots, silent
  /// until its first point, without allocating; `prepared` then holds what the index held
  /// before, for the caller to free off the audio thread. False when the index is taken or out
  /// of range, or no run of slots is long enough.
  bool install(Prepared& prepared, uint32_t index) noexcept;
  /// prepare() and install() at the first index never used; returns it. Throws InputError.
  int add_contact(const ContactSpec& spec);
  /// Ends the contact at `sample` (its force fades out from there) and frees it once its modes
  /// have rung down (retired()).
  void remove(int contact, uint64_t sample);
  /// Indices freed since clear_retired() (up to max_contacts).
  std::span<const uint32_t> retired() const { return retired_; }
  void clear_retired() { retired_.clear(); }
  bool live(int contact) const {
    return contact >= 0 && std::size_t(contact) < contacts_.size() && contacts_[contact].live;
  }
  /// Queues a control point. False (and dropped) when the queue is full, the point is earlier
  /// than the last one queued, the contact has ended, or a value is not finite or negative, or a
  /// vertex lies past its body's surface points.
  bool push(int contact, const ContactPoint& point);
  /// The contact's force fades out from `sample` on (and the contact takes no more points).
  void end(int contact, uint64_t sample);
  /// A body's per-mode listener gains and pan (they ramp as the filterbank ramps gains).
  void set_gains(int contact, int body, std::span<const float> gains, float left, float right);

  /// Writes each contact's input for samples [now, now + frames) into row stream_base + k of
  /// `rows` (stream-major, `frames` per row), updates drive gains whose point changed, and frees
  /// the contacts removed that have rung down.
  void render(uint64_t now, uint32_t frames, float* rows);
  /// A contact's normal-direction force (N, faded) over the last prepare()'s samples.
  std::span<const float> force(int contact) const { return contacts_.at(contact).force; }
  /// Input streams the filterbank must be given: stream_base + contacts.
  uint32_t streams() const { return opt_.stream_base + count_; }
  /// Indices used so far (live or not): contacts [0, contact_count()) have streams.
  uint32_t contact_count() const { return count_; }
  /// The sample after which no contact's force is non-zero (0 before any end; UINT64_MAX while
  /// one has not ended).
  uint64_t silent_from() const;

 private:
  struct Body {
    ObjectModes modes;
    uint32_t first_slot = 0, count = 0;
    int64_t vertex = -1;  // the point the drive gains were last set for
  };
  struct Contact {
    bool live = false;
    bool fading = false;  // removed, rung down: its gains ramping to zero
    uint64_t retire_at = UINT64_MAX, free_at = 0;
    uint64_t ring_down = 0;  // samples its slowest mode takes to fall by 60 dB
    uint32_t first_slot = 0, slots = 0;
    std::string name;
    std::array<Body, 2> bodies;
    int body_count = 1;
    std::unique_ptr<SurfaceProfile> profile;
    std::unique_ptr<ContactExcitation> excitation;
    std::vector<ContactPoint> ring;  // capacity max_points
    std::size_t head = 0, size = 0;
    uint64_t begin = 0, end = UINT64_MAX;
    std::vector<float> force;  // the last block's, max_frames
    float f1 = 0, f2 = 0;      // the force one and two samples before the block
  };
  const ContactPoint& at(const Contact& c, std::size_t i) const {
    return c.ring[(c.head + i) % c.ring.size()];
  }
  void drive_gains(Contact& c, uint32_t stream, const ContactPoint& p);
  void fill(Contact& c, uint64_t now, uint32_t frames);
  bool retire(Contact& c, uint32_t index, uint64_t now);

  Filterbank& fb_;
  ContactBankOptions opt_;
  SlotLease lease_;
  uint32_t slot_end_ = 0;  // slots [lease_.begin, +slot_end_) have been used
  uint32_t count_ = 0;
  SlotRuns free_runs_;
  std::vector<Contact> contacts_;  // max_contacts places
  std::vector<uint32_t> retired_;
  std::vector<float> force_, slip_, roll_;  // scratch, max_frames each
};

struct ContactBank::Prepared {
  Contact contact;
};

}  // namespace chladni::runtime
