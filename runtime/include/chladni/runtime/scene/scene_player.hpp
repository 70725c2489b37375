#pragma once
// A live scene: sounding objects placed in the world and a listener. The one place that turns
// objects into voices, poses into per-mode listener gains (transfer where its fit is usable,
// else the compact-source gain over distance; scene_objects.hpp) and constant-power pan, and
// impacts into strikes with their contact force; its shakers (PhISEM particles in or at an
// object) share the filterbank through their own slot lease and follow the objects' gains.
// SceneTimeline drives one from a Scene's timeline; an engine drives one directly.
//
// Threading: add_object() and add_shaker() allocate (a control thread, never during render());
// move(), set_listener(), impact(), shake() and render() do not allocate once objects are added.
// A live scene (an engine's) changes while it plays: prepare_object() allocates off the audio
// thread, install() places the object between renders without allocating, and a removed object's
// place is reported by retired() once its fade has ended, for the next install().
#include <chrono>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "chladni/core/scene.hpp"
#include "chladni/runtime/contact/contact_bank.hpp"
#include "chladni/runtime/modal/synth.hpp"
#include "chladni/runtime/modal/transfer_gains.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "chladni/runtime/thread_pool.hpp"

namespace chladni::gpu {
class Context;
}

namespace chladni::runtime {

struct PlayerOptions {
  double sample_rate = 48000;
  double gain = 1.0;  ///< scales every object
  SynthOptions synth;
  /// Listener gains on this device once the objects with transfer have gpu_gain_modes modes
  /// (null: always on the CPU); far-field maps on the CPU from map_gain_modes modes.
  std::shared_ptr<gpu::Context> gain_device;
  std::size_t gpu_gain_modes = 20000;
  std::size_t map_gain_modes = 4096;
  /// Filterbank slots and voices for shakers, leased before the synth's (0: no shakers). A GPU
  /// filterbank needs max_streams() >= max_shakers: the particles are then made on the device.
  uint32_t shaker_slots = 0;
  uint32_t max_shakers = 0;
  uint64_t seed = 1;  ///< the shakers' random streams
  /// Filterbank slots and contacts for continuous contacts (contact_bank.hpp), leased after the
  /// shakers' and before the synth's; their input streams follow the shakers' (0: none).
  uint32_t contact_slots = 0;
  uint32_t max_contacts = 0;
  uint32_t contact_points = 64;  ///< control points queued per contact
  /// Places reserved for objects, so that install() never allocates (0: grown as added).
  uint32_t max_objects = 0;
};

class ScenePlayer {
 public:
  /// The player's voices take the synth's budget of `filterbank` (options.synth).
  ScenePlayer(Filterbank& filterbank, const PlayerOptions& options);
  ~ScenePlayer();

  /// Adds an object (its modes, pose and gain); returns its index. Objects sharing a Transfer
  /// share its coefficients and maps. Control thread.
  std::size_t add_object(const ObjectModes& modes, const Vec3& position, const Quat& orientation,
                         double gain = 1.0);
  /// Silences an object: its gains ramp to zero over the filterbank's gain ramp, then its slots
  /// are freed. Commands for it are refused from then on.
  void remove(std::size_t object);
  bool active(std::size_t object) const { return objects_.at(object).voice >= 0; }
  /// Prepares the listener-gain tables for the objects added so far (maps, device buffers);
  /// done by the first update otherwise. Control thread.
  void finish_objects();

  /// An object made ready off the audio thread; install() takes it.
  struct PreparedObject;
  /// Prepares an object (its voice, gains and scratch; allocates). `table` holds the transfer of
  /// `modes` as one object (object_transfer_table(); shared by instances, and it must outlive
  /// the object); null when `modes` has no transfer. Throws InputError on bad values.
  std::unique_ptr<PreparedObject> prepare_object(const ObjectModes& modes,
                                                 const TransferTable* table, const Vec3& position,
                                                 const Quat& orientation, double gain) const;
  /// Places `prepared` at index `object` (the next new index, or one retired()) without
  /// allocating; `prepared` then holds what the place held before, to be freed off the audio
  /// thread. False when the place is taken, beyond max_objects, or every voice is in use.
  bool install(std::size_t object, PreparedObject& prepared) noexcept;
  /// Objects removed whose fade has ended since clear_retired(): their places may be installed
  /// again. Recorded up to max_objects.
  std::span<const uint32_t> retired() const { return retired_; }
  void clear_retired() {
    retired_.clear();
    retired_shakers_.clear();
    if (contacts_) contacts_->clear_retired();
  }

  /// Adds a shaker at `object`: a voice whose resonances are the object's modes (`resonate`:
  /// they take the object's listener gains) or an instrument's own (they take the object's
  /// distance spreading); both take its pan. Silent until shaken. Control thread.
  int add_shaker(std::size_t object, const ShakerVoice& voice, bool resonate);
  /// A shaker made ready off the audio thread; install_shaker() takes it.
  struct PreparedShaker;
  /// Validates and builds a shaker's voice (allocates). Throws InputError on bad values or when
  /// the player has no room for shakers.
  std::unique_ptr<PreparedShaker> prepare_shaker(const ShakerVoice& voice, bool resonate) const;
  /// Places `prepared` at index `shaker` (shaker_count(), or one retired_shakers() reported) on
  /// `object`, without allocating; `prepared` then holds what the index held before. False
  /// when the index is taken, the object is not live, a resonating voice's resonances are not
  /// the object's modes, or the bank has no room.
  bool install_shaker(int shaker, std::size_t object, PreparedShaker& prepared);
  /// Fades a shaker out over the gain ramp; its voice is then removed and its index reported by
  /// retired_shakers(). An object's removal removes its shakers so.
  void remove_shaker(int shaker);
  std::span<const uint32_t> retired_shakers() const { return retired_shakers_; }
  /// Adds `energy` (0-1) to a shaker at fractional sample `offset` of the next render; false
  /// when it cannot be taken this render (the shake list is full) or the shaker's object was
  /// removed.
  bool shake(int shaker, float energy, uint32_t offset);
  std::size_t shaker_count() const { return shakers_.size(); }
  std::size_t shaker_object(int shaker) const { return shakers_.at(shaker).object; }

  /// A continuous contact on `object`, pressed against `other` where that is >= 0: its modes
  /// (each body's) take the contact lease's slots and follow the objects' gains and pan. Silent
  /// until its first point. Throws InputError (naming `name`) when the player has no room, the
  /// roughness is out of range or an object is not live. Control thread.
  int add_contact(std::size_t object, long other, const Roughness& roughness, uint64_t seed,
                  const std::string& name);
  /// A contact built off the audio thread between `body` and, unless null, `other` (their
  /// modes), for install_contact(). Throws InputError naming `name`.
  std::unique_ptr<ContactBank::Prepared> prepare_contact(const ObjectModes& body,
                                                         const ObjectModes* other,
                                                         const Roughness& roughness, uint64_t seed,
                                                         const std::string& name) const;
  /// Places a prepared contact at `index` on live objects, without allocating; `prepared` then
  /// holds what the index held before. False when the index is taken or out of range, an object
  /// is not live, or the contacts' slots are full.
  bool install_contact(int index, std::size_t object, long other,
                       ContactBank::Prepared& prepared) noexcept;
  /// Ends a contact now; its index is reported by retired_contacts() once its modes have rung
  /// down. An object's removal ends (but does not remove) the contacts that touch it.
  void remove_contact(int contact);
  std::span<const uint32_t> retired_contacts() const {
    return contacts_ ? contacts_->retired() : std::span<const uint32_t>{};
  }
  /// Queues a control point of a contact (contact_bank.hpp); false when refused.
  bool push_contact(int contact, const ContactPoint& point);
  /// The contact's force fades out from absolute sample `sample`.
  void end_contact(int contact, uint64_t sample);
  /// null without contacts.
  const ContactBank* contacts() const { return contacts_.get(); }

  void move(std::size_t object, const Vec3& position, const Quat& orientation);
  void set_listener(const Listener& listener);
  /// Strikes `object`: the event's point or vertex, direction, impulse and contact time, from
  /// fractional sample `start` of the next render (-1 < start < max_frames()).
  void impact(std::size_t object, const ImpactEvent& event, double start);

  /// Recomputes the listener gains when a pose changed since the last update; true if it did.
  bool update_gains();
  /// Renders `frames` interleaved frames (updating gains first if needed), shakers included.
  void render(uint32_t frames, float* out);

  /// The last update's per-mode gains and pan of an object, and its distance spreading (gain /
  /// distance): for other voices placed at the object (shakers).
  std::span<const float> gains(std::size_t object) const { return objects_[object].gains; }
  const float* pan(std::size_t object) const { return objects_[object].pan; }
  double spreading(std::size_t object) const { return objects_[object].spread; }

  const Vec3& position(std::size_t object) const { return objects_.at(object).position; }
  const Quat& orientation(std::size_t object) const { return objects_.at(object).orientation; }
  const Listener& listener() const { return listener_; }
  Synth& synth() { return synth_; }
  const Synth& synth() const { return synth_; }
  std::size_t object_count() const { return objects_.size(); }
  std::size_t mode_count(std::size_t object) const { return objects_.at(object).gains.size(); }
  const ObjectModes& modes(std::size_t object) const { return objects_.at(object).modes; }
  /// Surface points an impact may name by vertex (0 without geometry).
  std::size_t points(std::size_t object) const { return surface_points(objects_.at(object).modes); }
  uint64_t gain_updates() const { return gain_updates_; }
  double gain_seconds() const { return gain_seconds_; }
  /// "cpu", "gpu" or "" when no object has transfer.
  std::string gain_backend() const;

 private:
  struct Object {
    ObjectModes modes;
    Synth::VoiceId voice = -1;
    Synth::VoiceId fading = -1;  // a removed object's voice until its fade ends
    uint64_t fade_end = 0;
    Vec3 position{0, 0, 0};
    Quat orientation{1, 0, 0, 0};
    double gain = 1;
    int table = -1;  // index in table_.objects
    // A live object's own transfer table (table = -1), its frame and gains.
    const TransferTable* own_table = nullptr;
    ListenerFrame own_frame;
    std::vector<float> own_gains;
    std::vector<float> gains;
    std::vector<std::complex<float>> coupling;
    float pan[2] = {1, 1};
    double spread = 1;
  };
  struct Shaker {
    std::size_t object = 0;
    bool resonate = false;
    std::vector<float> flat;  // an instrument's gains, one per resonance (zeros silence it)
    bool dead = true;         // removed, or its object was (whatever takes the place later is
                              // another)
    bool fading = false;      // its voice is removed at fade_end
    uint64_t fade_end = 0;
  };
  void apply_gains(Object& object);
  void own_transfer_gains(Object& object);
  void retire(std::size_t object);
  void end_shaker_fades();
  void apply_shaker_gains(int shaker);
  void apply_contact_gains();
  void end_contacts_of(std::size_t object);
  DriveInput drive(uint32_t frames);

  Filterbank& fb_;
  PlayerOptions opt_;
  std::unique_ptr<ShakerBank> bank_;       // leases its slots before the synth
  std::unique_ptr<ContactBank> contacts_;  // and these after the shakers'
  Synth synth_;
  std::vector<std::array<long, 2>> contact_objects_;  // per contact: its objects (-1: none)
  std::vector<float> drive_;  // the shakers' and contacts' input rows, when both play
  std::vector<Shaker> shakers_;
  std::size_t fading_ = 0;  // removed objects still fading out
  std::size_t shakers_fading_ = 0;
  std::vector<Object> objects_;
  std::vector<uint32_t> retired_, retired_shakers_;
  Listener listener_;
  bool dirty_ = true;
  // Listener gains from transfer.
  TransferTable table_;
  ListenerFrame frame_;
  std::vector<Vec3> listener_local_;
  std::vector<float> table_gains_;
  std::unique_ptr<ThreadPool> pool_;
  std::unique_ptr<GpuTransferGains> gpu_gains_;
  bool tables_ready_ = false;
  uint64_t gain_updates_ = 0;
  double gain_seconds_ = 0;
};

struct ScenePlayer::PreparedShaker {
  std::unique_ptr<ShakerBank::PreparedVoice> voice;
  Shaker shaker;
};

struct ScenePlayer::PreparedObject {
  Object object;
  Synth::VoiceData voice;
};

/// One object's transfer as a table of its own, for prepare_object(); with far-field maps when
/// `maps`.
std::unique_ptr<TransferTable> object_transfer_table(const Transfer& transfer, bool maps);

}  // namespace chladni::runtime
