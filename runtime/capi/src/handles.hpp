#pragma once
// The C API's handles and helpers (internal).
//
// Three threads meet here. The control thread owns banks and the object places' bookkeeping; it
// hands prepared objects and removals to the audio thread through `changes`, and takes back what
// the audio thread is done with (retired places, the storage an install swapped out) through
// `returns`: every allocation and free stays off the audio thread. The game thread posts commands
// through `queue`, checking handles against the places' atomic ids; the audio thread checks them
// again against what it has installed, so a command for an object removed meanwhile is dropped.
#include <atomic>
#include <cmath>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "chladni/chladni.h"
#include "chladni/core/error.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/scene/scene_player.hpp"
#include "spsc_queue.hpp"

namespace chladni::capi {

enum class Kind : uint8_t { Impact, Move, Listener, Shake, Contact };

// One posted command, plain data (copied through the queue).
struct Command {
  Kind kind;
  uint64_t object;  // the object's handle id (a shaker's object for Shake)
  uint64_t shaker;  // Shake: the shaker's handle id; Contact: the contact's
  uint64_t other;   // Contact: the other object's handle id (0: none)
  double time;
  double impulse, contact;  // a shake's energy; a contact's normal force and slip speed
  int64_t vertex;
  // direction/point/-, position/forward/up, orientation; a contact's point/other point/rolling
  double a[3], b[3], c[3], q[4];
};

// A paper sheet's audio on its way from the control thread, which renders each posted frame, to
// the audio thread, which mixes it in at its time.
struct PaperStream {
  static constexpr uint64_t kNotStarted = ~uint64_t{0};
  explicit PaperStream(std::size_t floats) : ring(floats) {}
  runtime::SpscRing ring;  // stereo, interleaved
  // The output sample of the sheet's first sample: set once, before its first samples are
  // written (the ring's release publishes it).
  std::atomic<uint64_t> start{kNotStarted};
  std::atomic<bool> ended{false};  // nothing more will be written
  // Audio thread: stereo frames consumed (played, or dropped for arriving after their time).
  uint64_t consumed = 0;
};

// Control -> audio: an object or a shaker to place, or one to remove; a paper stream to mix.
struct Change {
  enum class Kind : uint8_t {
    Spawn,
    Remove,
    AddShaker,
    RemoveShaker,
    AddPaper,
    AddContact,
    RemoveContact
  } kind;
  uint32_t place;
  uint64_t id;
  uint64_t object = 0;  // AddShaker, AddContact: its object's handle id
  uint64_t other = 0;   // AddContact: the other object's (0: none)
  runtime::ScenePlayer::PreparedObject* prepared = nullptr;  // Spawn
  runtime::ScenePlayer::PreparedShaker* shaker = nullptr;    // AddShaker
  PaperStream* paper = nullptr;                              // AddPaper
  runtime::ContactBank::Prepared* contact = nullptr;         // AddContact
};

// Audio -> control: a place whose object or shaker has faded out, or storage to free.
struct Return {
  enum class Kind : uint8_t {
    Retired,
    Garbage,
    Refused,
    ShakerRetired,
    ShakerGarbage,
    PaperRetired,
    ContactRetired,
    ContactGarbage
  } kind;
  uint32_t place;
  runtime::ScenePlayer::PreparedObject* prepared = nullptr;  // Garbage, Refused
  runtime::ScenePlayer::PreparedShaker* shaker = nullptr;    // ShakerGarbage (also refused)
  runtime::ContactBank::Prepared* contact = nullptr;         // ContactGarbage (also refused)
};

struct Bank {
  std::unique_ptr<ModalModel> model;  // soundbanks
  std::vector<InlineMode> inline_modes;
  runtime::ObjectModes modes;
  std::unique_ptr<runtime::TransferTable> table;  // the model's transfer, for its objects
  uint64_t id = 0;                                // its handle's, the key in chladni_runtime::banks
  double mass = 0;       // kg: the surface's volume times the density (0 for inline modes)
  uint32_t objects = 0;  // objects placed and not yet retired
  bool released = false;
};

// An object place. `id` and `points` are read by the game thread; the rest is the control
// thread's.
struct Place {
  std::atomic<uint64_t> id{0};  // the live object's handle id (0: none)
  std::atomic<uint64_t> points{0};
  Bank* bank = nullptr;  // while spawned and not yet retired
  uint32_t generation = 0;
};

// A shaker place. `id` and `object` are read by the game thread; the rest is the control
// thread's.
struct ShakerPlace {
  std::atomic<uint64_t> id{0};      // the live shaker's handle id (0: none)
  std::atomic<uint64_t> object{0};  // its object's handle id
  uint32_t generation = 0;
};

// A contact place. `id`, `object`, `other` and `box` are read by the game thread, which may
// read them for a handle the control thread is replacing (the audio thread then drops what it
// posted); the rest is the control thread's.
struct ContactPlace {
  std::atomic<uint64_t> id{0};  // the live contact's handle id (0: none)
  std::atomic<uint64_t> object{0}, other{0};
  // Per body: the box a posted point must lie in (its surface points' box grown by a tenth of
  // its diagonal; infinite without geometry): min x y z, max x y z.
  std::atomic<double> box[2][6] = {};
  uint32_t generation = 0;
};

struct PaperSheet;  // papers.cpp: the control thread's side of a sheet
struct PaperSheetDeleter {
  void operator()(PaperSheet* p) const;
};
using PaperSheetPtr = std::unique_ptr<PaperSheet, PaperSheetDeleter>;

/// Records `message` as this thread's last error; returns `status`.
chladni_status fail(chladni_status status, std::string message);

// Runs `f`, turning every exception into a status and a message naming the call.
template <class F>
chladni_status guarded(const char* call, F&& f) {
  try {
    return f();
  } catch (const InputError& e) {
    return fail(CHLADNI_INPUT_ERROR, std::string(call) + ": " + e.what());
  } catch (const gpu::NoDeviceError& e) {
    return fail(CHLADNI_NO_DEVICE, std::string(call) + ": " + e.what());
  } catch (const std::exception& e) {
    return fail(CHLADNI_INTERNAL_ERROR, std::string(call) + ": " + e.what());
  } catch (...) {
    return fail(CHLADNI_INTERNAL_ERROR, std::string(call) + ": unknown error");
  }
}

// The largest values that still play: a coordinate (m), an object's gain, an impulse (N s).
// Past them a mode's gain or kick overflows a float, and the audio thread would have to drop it.
constexpr double kMaxCoordinate = 1e9, kMaxGain = 1e6, kMaxImpulse = 1e6;

/// InputError unless `v` holds 3 numbers within kMaxCoordinate (and, with `nonzero`, not zero).
void need_vector(const double* v, const char* what, bool nonzero = true);
/// The unit quaternion of `q` (w, x, y, z); InputError when not finite or zero.
Quat unit_quaternion(const double* q);

/// A handle id: the place in the low 32 bits, its generation (from 1) in the high ones.
inline uint64_t handle_id(uint32_t place, uint32_t generation) {
  return (uint64_t{generation} << 32) | place;
}
inline uint32_t place_of(uint64_t id) {
  return static_cast<uint32_t>(id & 0xffffffffu);
}
/// The generation after `g`, skipping 0 (an id of 0 is none).
inline uint32_t next_generation(uint32_t g) {
  return g + 1 == 0 ? 1 : g + 1;
}

}  // namespace chladni::capi

struct chladni_runtime {
  explicit chladni_runtime(const chladni_config& c);
  ~chladni_runtime();
  // Control thread.
  void reclaim();
  chladni::capi::Bank& bank(chladni_bank handle) const;
  void check_time(double time) const;
  // Audio thread.
  void drain();
  void take_changes();
  void apply_due(uint64_t t, uint32_t frames);
  void apply_contacts(uint64_t t);
  uint32_t until_next_pose(uint32_t frames) const;
  uint64_t sample_of(const chladni::capi::Command& c) const;
  uint32_t max_shakers() const { return config.shaker_slots ? config.max_shakers : 0; }
  uint32_t max_contacts() const { return config.contact_slots ? config.max_contacts : 0; }
  void give_back(const chladni::capi::Return& r) {
    if (!returns.push(r)) ++lost_returns;  // sized so that it cannot fill
  }
  void mix_papers(float* out, uint64_t start, uint32_t frames);
  void reclaim_paper(uint32_t place);
  bool installed(uint64_t object) const {
    const uint32_t k = chladni::capi::place_of(object);
    return k < installed_ids.size() && installed_ids[k] == object;
  }

  chladni_config config;
  std::unique_ptr<chladni::runtime::Filterbank> fb;
  std::string name;
  std::unique_ptr<chladni::runtime::ScenePlayer> player;
  // Control thread.
  std::unordered_map<uint64_t, std::unique_ptr<chladni::capi::Bank>> banks;
  uint64_t next_bank = 1;
  std::vector<uint32_t> free_places, free_shaker_places, free_paper_places, free_contact_places;
  std::vector<chladni::capi::PaperSheetPtr> papers;  // per paper place
  std::vector<uint32_t> paper_generations;
  // Shared.
  std::unique_ptr<chladni::capi::Place[]> places;
  std::unique_ptr<chladni::capi::ShakerPlace[]> shakers;
  std::unique_ptr<chladni::capi::ContactPlace[]> contacts;
  chladni::runtime::SpscQueue<chladni::capi::Command> queue;
  chladni::runtime::SpscQueue<chladni::capi::Change> changes;
  chladni::runtime::SpscQueue<chladni::capi::Return> returns;
  // Audio thread.
  std::vector<uint64_t> installed_ids;          // per place: the object installed there
  std::vector<uint64_t> installed_shaker_ids;   // per shaker place: the shaker installed there
  std::vector<uint64_t> installed_contact_ids;  // per contact place: the contact there
  std::vector<chladni::capi::PaperStream*> installed_papers;  // per paper place
  std::vector<chladni::capi::Command> pending;  // drained commands, by time; capacity fixed
  uint64_t lost_returns = 0;                    // returns dropped on a full queue (a bug)
  uint64_t dropped_commands = 0;  // commands the player refused (values past what plays)
  uint64_t now = 0;               // samples rendered (audio thread)
  // The listener chladni_listener_set last posted (game thread), for paper sheets that follow
  // it (control thread): position, forward, up, under a sequence count (odd while written).
  std::atomic<uint64_t> listener_seq{0};
  std::atomic<double> listener[9] = {};
  std::atomic<uint64_t> clock{0};  // `now`, published for chladni_runtime_time on other threads
};

namespace chladni::capi {

// The place of the live handle `id` among `count` places (objects', shakers' or contacts'), for
// the game thread; InputError naming the `noun` and how a handle stops being live otherwise.
template <class P>
uint32_t live_place(uint64_t id, const P* places, uint32_t count, const char* noun,
                    const char* why) {
  const uint32_t k = place_of(id);
  if (id == 0 || k >= count || places[k].id.load(std::memory_order_acquire) != id)
    throw InputError(std::string("no ") + noun + " " + std::to_string(id) + " (" + why + ")");
  return k;
}

inline uint32_t live(const chladni_runtime* rt, chladni_object object) {
  return live_place(object.id, rt->places.get(), rt->config.max_objects, "object",
                    "never spawned, or removed");
}

inline uint32_t live_shaker(const chladni_runtime* rt, chladni_shaker shaker) {
  return live_place(shaker.id, rt->shakers.get(), rt->max_shakers(), "shaker",
                    "never added, or removed");
}

inline chladni_status post(chladni_runtime* rt, const Command& c) {
  return rt->queue.push(c) ? CHLADNI_OK : fail(CHLADNI_QUEUE_FULL, "the command queue is full");
}

}  // namespace chladni::capi
