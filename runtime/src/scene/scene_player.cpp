#include "chladni/runtime/scene/scene_player.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <thread>

#include "chladni/core/error.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"

namespace chladni::runtime {
namespace {

// Spherical spreading relative to 1 m, clamped so an object at the listener stays finite.
constexpr double kMinDistance = 0.1;
// Listener-gain tables this large spread their updates over all cores.
constexpr std::size_t kThreadedGainModes = 4096;

std::unique_ptr<ShakerBank> make_bank(Filterbank& fb, const PlayerOptions& o) {
  if (o.shaker_slots == 0 || o.max_shakers == 0) return nullptr;
  ShakerBankOptions bo;
  bo.sample_rate = o.sample_rate;
  bo.slots = o.shaker_slots;
  bo.max_voices = o.max_shakers;
  bo.seed = o.seed;
  bo.reserve_all = o.max_objects > 0;  // a live scene: voices come and go while it plays
  // A pipelined device takes no input stage: the particles are then made on the CPU.
  bo.excitation =
      fb.device() && !fb.device()->pipelined() ? ExcitationBackend::Gpu : ExcitationBackend::Cpu;
  return std::make_unique<ShakerBank>(fb, bo);
}

std::unique_ptr<ContactBank> make_contacts(Filterbank& fb, const PlayerOptions& o) {
  if (o.contact_slots == 0 || o.max_contacts == 0) return nullptr;
  ContactBankOptions co;
  co.sample_rate = o.sample_rate;
  co.slots = o.contact_slots;
  co.max_contacts = o.max_contacts;
  co.stream_base = o.shaker_slots && o.max_shakers ? o.max_shakers : 0;
  co.ramp = std::max<uint32_t>(fb.gain_ramp(), 1);
  co.max_points = o.contact_points;
  return std::make_unique<ContactBank>(fb, co);
}

}  // namespace

ScenePlayer::ScenePlayer(Filterbank& fb, const PlayerOptions& o)
    : fb_(fb),
      opt_(o),
      bank_(make_bank(fb, o)),
      contacts_(make_contacts(fb, o)),
      synth_(fb, o.synth) {
  if (contacts_) {
    contact_objects_.assign(o.max_contacts, {-1, -1});
    drive_.assign(std::size_t{contacts_->streams() + o.max_contacts} * fb.max_frames(), 0.0f);
  }
  if (!std::isfinite(o.gain)) throw InputError("scene gain must be finite");
  shakers_.reserve(o.max_shakers);
  retired_shakers_.reserve(o.max_shakers);
  objects_.reserve(o.max_objects);
  retired_.reserve(o.max_objects);
}

ScenePlayer::~ScenePlayer() = default;

std::size_t ScenePlayer::add_object(const ObjectModes& modes, const Vec3& position,
                                    const Quat& orientation, double gain) {
  if (!std::isfinite(gain)) throw InputError("object gain must be finite");
  if (modes.transfer && modes.transfer->mode_count() != modes.modes.size())
    throw InternalError("player: transfer and modes differ in count");
  Object o;
  o.modes = modes;
  o.voice = synth_.start_voice(modes.modes);
  o.position = position;
  o.orientation = orientation;
  o.gain = gain;
  o.gains.assign(modes.modes.size(), 0.0f);
  o.coupling.assign(modes.modes.size(), {0.0f, 0.0f});
  objects_.push_back(std::move(o));
  tables_ready_ = false;
  dirty_ = true;
  return objects_.size() - 1;
}

void ScenePlayer::finish_objects() {
  std::size_t transfer_modes = 0;
  for (const Object& o : objects_)
    if (o.modes.transfer && !o.own_table) transfer_modes += o.modes.modes.size();
  const bool on_device = opt_.gain_device && transfer_modes >= opt_.gpu_gain_modes;
  pool_ = std::make_unique<ThreadPool>(transfer_modes >= kThreadedGainModes
                                           ? int(std::max(1u, std::thread::hardware_concurrency()))
                                           : 1);
  table_ = TransferTable{};
  // Maps pay for their build once many modes are updated; the device streams the series.
  if (on_device || transfer_modes < opt_.map_gain_modes) table_.map_options.reset();
  for (std::size_t k = 0; k < objects_.size(); ++k) {
    Object& o = objects_[k];
    o.table = -1;
    if (!o.modes.transfer || o.own_table) continue;
    std::size_t same = 0;
    while (same < k && objects_[same].modes.transfer != o.modes.transfer) ++same;
    o.table = static_cast<int>(same < k ? table_.add_instance(objects_[same].table)
                                        : table_.add(*o.modes.transfer, pool_.get()));
  }
  listener_local_.assign(table_.objects.size(), Vec3{0, 0, 0});
  table_gains_.assign(table_.mode_count(), 0.0f);
  gpu_gains_.reset();
  if (on_device) gpu_gains_ = std::make_unique<GpuTransferGains>(opt_.gain_device, table_);
  // Size the frame's scratch now: updates then allocate nothing.
  if (table_.mode_count() > 0) frame_.update(table_, listener_local_, gpu_gains_ != nullptr);
  tables_ready_ = true;
  dirty_ = true;
}

std::unique_ptr<TransferTable> object_transfer_table(const Transfer& transfer, bool maps) {
  auto table = std::make_unique<TransferTable>();
  if (!maps) table->map_options.reset();
  table->add(transfer);
  return table;
}

std::unique_ptr<ScenePlayer::PreparedObject> ScenePlayer::prepare_object(const ObjectModes& modes,
                                                                         const TransferTable* table,
                                                                         const Vec3& position,
                                                                         const Quat& orientation,
                                                                         double gain) const {
  if (!std::isfinite(gain)) throw InputError("object gain must be finite");
  if (modes.transfer && (!table || table->mode_count() != modes.modes.size()))
    throw InternalError("player: a live object with transfer needs its table");
  auto p = std::make_unique<PreparedObject>();
  p->voice = Synth::prepare_voice(modes.modes);
  Object& o = p->object;
  o.modes = modes;
  o.position = position;
  o.orientation = orientation;
  o.gain = gain;
  o.gains.assign(modes.modes.size(), 0.0f);
  o.coupling.assign(modes.modes.size(), {0.0f, 0.0f});
  if (modes.transfer) {
    o.own_table = table;
    o.own_gains.assign(modes.modes.size(), 0.0f);
    const Vec3 origin{0, 0, 0};
    o.own_frame.update(*table, std::span(&origin, 1));  // sized here: updates allocate nothing
  }
  return p;
}

bool ScenePlayer::install(std::size_t k, PreparedObject& p) noexcept {
  if (k > objects_.size() || k >= objects_.capacity()) return false;
  if (k < objects_.size() && (objects_[k].voice >= 0 || objects_[k].fading >= 0)) return false;
  const Synth::VoiceId v = synth_.start_voice(p.voice);
  if (v < 0) return false;
  p.object.voice = v;
  p.object.fading = -1;
  p.object.table = -1;
  if (k == objects_.size())
    objects_.push_back(std::move(p.object));  // within the reserved capacity
  else
    std::swap(objects_[k], p.object);
  dirty_ = true;
  return true;
}

void ScenePlayer::retire(std::size_t k) {
  if (retired_.size() < retired_.capacity()) retired_.push_back(static_cast<uint32_t>(k));
}

std::string ScenePlayer::gain_backend() const {
  return table_.mode_count() == 0 ? "" : gpu_gains_ ? "gpu" : "cpu";
}

std::unique_ptr<ScenePlayer::PreparedShaker> ScenePlayer::prepare_shaker(const ShakerVoice& voice,
                                                                         bool resonate) const {
  if (!bank_) throw InputError("the player has no room for shakers (shaker_slots)");
  auto p = std::make_unique<PreparedShaker>();
  p->voice = ShakerBank::prepare_voice(voice);
  p->shaker.resonate = resonate;
  p->shaker.flat.assign(voice.resonances.size(), 0.0f);
  return p;
}

bool ScenePlayer::install_shaker(int k, std::size_t object, PreparedShaker& p) {
  if (!bank_ || k < 0 || static_cast<std::size_t>(k) > shakers_.size() ||
      static_cast<std::size_t>(k) >= shakers_.capacity() || object >= objects_.size() ||
      objects_[object].voice < 0)
    return false;
  if (static_cast<std::size_t>(k) < shakers_.size() && (!shakers_[k].dead || shakers_[k].fading))
    return false;
  if (p.shaker.resonate && p.shaker.flat.size() != objects_[object].modes.modes.size())
    return false;
  if (bank_->live(k) || !bank_->add_voice(*p.voice, static_cast<uint32_t>(k))) return false;
  p.shaker.object = object;
  p.shaker.dead = false;
  p.shaker.fading = false;
  if (static_cast<std::size_t>(k) == shakers_.size())
    shakers_.push_back(std::move(p.shaker));  // within the reserved capacity
  else
    std::swap(shakers_[k], p.shaker);
  dirty_ = true;
  return true;
}

int ScenePlayer::add_shaker(std::size_t object, const ShakerVoice& voice, bool resonate) {
  const Object& o = objects_.at(object);
  if (o.voice < 0) throw InputError("object " + std::to_string(object) + " was removed");
  if (resonate && voice.resonances.size() != o.modes.modes.size())
    throw InternalError("player: a resonating shaker needs one resonance per mode");
  std::unique_ptr<PreparedShaker> p = prepare_shaker(voice, resonate);
  const int k = static_cast<int>(shakers_.size());
  if (static_cast<uint32_t>(k) >= opt_.max_shakers)
    throw InputError("shaker bank is full (" + std::to_string(opt_.max_shakers) + " voices)");
  if (!install_shaker(k, object, *p))
    throw InputError("voice '" + voice.name + "' needs " + std::to_string(voice.resonances.size()) +
                     " filterbank slots; the shakers' slots are full");
  return k;
}

void ScenePlayer::remove_shaker(int k) {
  if (k < 0 || static_cast<std::size_t>(k) >= shakers_.size()) return;
  Shaker& sh = shakers_[k];
  if (sh.dead) return;
  sh.dead = true;
  apply_shaker_gains(k);  // its gains ramp to zero
  sh.fading = true;
  sh.fade_end = synth_.time() + fb_.gain_ramp();
  ++shakers_fading_;
  if (fb_.gain_ramp() == 0) end_shaker_fades();
}

// Removes the voices of the shakers whose fade has ended.
void ScenePlayer::end_shaker_fades() {
  for (std::size_t k = 0; shakers_fading_ > 0 && k < shakers_.size(); ++k) {
    Shaker& sh = shakers_[k];
    if (!sh.fading || synth_.time() < sh.fade_end) continue;
    bank_->remove_voice(static_cast<int>(k));
    sh.fading = false;
    --shakers_fading_;
    if (retired_shakers_.size() < retired_shakers_.capacity())
      retired_shakers_.push_back(static_cast<uint32_t>(k));
  }
}

bool ScenePlayer::shake(int k, float energy, uint32_t offset) {
  if (!bank_ || k < 0 || static_cast<std::size_t>(k) >= shakers_.size()) return false;
  if (shakers_[k].dead) return false;
  return bank_->shake(k, energy, offset);
}

void ScenePlayer::apply_shaker_gains(int k) {
  Shaker& sh = shakers_[k];
  const Object& o = objects_[sh.object];
  if (o.voice < 0 || sh.dead) {  // removed: a zero pan silences every resonance
    bank_->set_gains(k, sh.flat, 0, 0);
  } else if (sh.resonate) {
    bank_->set_gains(k, o.gains, o.pan[0], o.pan[1]);
  } else {
    std::fill(sh.flat.begin(), sh.flat.end(), static_cast<float>(o.spread));
    bank_->set_gains(k, sh.flat, o.pan[0], o.pan[1]);
  }
}

void ScenePlayer::move(std::size_t k, const Vec3& position, const Quat& orientation) {
  Object& o = objects_.at(k);
  o.position = position;
  o.orientation = orientation;
  dirty_ = true;
}

void ScenePlayer::remove(std::size_t k) {
  Object& o = objects_.at(k);
  if (o.voice < 0) return;
  if (contacts_) end_contacts_of(k);
  // Fade out over the gain ramp, then free the slots (render()); at once without a ramp.
  std::fill(o.gains.begin(), o.gains.end(), 0.0f);
  synth_.set_mode_gains(o.voice, o.gains);
  if (fb_.gain_ramp() == 0) {
    synth_.stop_voice(o.voice);
    retire(k);
  } else {
    o.fading = o.voice;
    o.fade_end = synth_.time() + fb_.gain_ramp();
    ++fading_;
  }
  o.voice = -1;
  for (std::size_t s = 0; s < shakers_.size(); ++s)
    if (shakers_[s].object == k && !shakers_[s].dead) remove_shaker(static_cast<int>(s));
}

void ScenePlayer::set_listener(const Listener& listener) {
  listener_ = listener;
  dirty_ = true;
}

void ScenePlayer::impact(std::size_t k, const ImpactEvent& event, double start) {
  Object& o = objects_.at(k);
  if (o.voice < 0) throw InputError("object " + std::to_string(k) + " was removed");
  update_gains();  // the modes this strike makes resident take the current gains
  impact_coupling(o.modes, event, o.coupling);
  synth_.strike(o.voice, o.coupling, start, event.contact_time);
}

void ScenePlayer::apply_gains(Object& o) {
  if (o.voice < 0) return;
  // Listener frame: right = forward x up.
  const Vec3 right = cross(listener_.forward, listener_.up);
  const double rn = std::sqrt(dot(right, right));
  const Vec3 d = sub(o.position, listener_.position);
  const double r = std::sqrt(dot(d, d));
  const double g = opt_.gain * o.gain;
  o.spread = g / std::max(r, kMinDistance);
  std::span<const float> xfer;
  if (o.own_table)
    xfer = o.own_gains;
  else if (o.table >= 0)
    xfer = std::span(table_gains_).subspan(table_.objects[o.table].first_mode, o.gains.size());
  listener_mode_gains(o.modes, xfer, g, o.spread, o.gains);
  synth_.set_mode_gains(o.voice, o.gains);
  if (fb_.channels() == 2) {
    const double s = r > 1e-9 && rn > 0 ? std::clamp(dot(d, right) / (r * rn), -1.0, 1.0) : 0.0;
    const double theta = (s + 1.0) * std::numbers::pi / 4.0;  // constant-power pan
    o.pan[0] = static_cast<float>(std::cos(theta));
    o.pan[1] = static_cast<float>(std::sin(theta));
    synth_.set_pan(o.voice, o.pan[0], o.pan[1]);
  }
}

void ScenePlayer::own_transfer_gains(Object& o) {
  const Vec3 local = rotate_inverse(o.orientation, sub(listener_.position, o.position));
  o.own_frame.update(*o.own_table, std::span(&local, 1));
  transfer_gains(*o.own_table, o.own_frame, o.own_gains);
}

bool ScenePlayer::update_gains() {
  if (!dirty_) return false;
  if (!tables_ready_) finish_objects();
  const auto t0 = std::chrono::steady_clock::now();
  for (const Object& o : objects_) {
    if (o.table >= 0)
      listener_local_[o.table] = rotate_inverse(o.orientation, sub(listener_.position, o.position));
  }
  if (table_.mode_count() > 0) {
    frame_.update(table_, listener_local_, gpu_gains_ != nullptr);
    if (gpu_gains_)
      gpu_gains_->compute(frame_, table_gains_);
    else
      transfer_gains(table_, frame_, table_gains_, pool_.get());
  }
  for (Object& o : objects_) {
    if (o.own_table && o.voice >= 0) own_transfer_gains(o);
    apply_gains(o);
  }
  for (std::size_t s = 0; s < shakers_.size(); ++s)  // remove() silenced the others once
    if (!shakers_[s].dead) apply_shaker_gains(static_cast<int>(s));
  apply_contact_gains();
  dirty_ = false;
  ++gain_updates_;
  gain_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return true;
}

void ScenePlayer::render(uint32_t frames, float* out) {
  update_gains();
  synth_.render(frames, out, drive(frames));
  if (bank_) bank_->finish(frames);
  if (shakers_fading_ > 0) end_shaker_fades();
  for (std::size_t k = 0; fading_ > 0 && k < objects_.size(); ++k) {
    Object& o = objects_[k];
    if (o.fading >= 0 && synth_.time() >= o.fade_end) {
      synth_.stop_voice(o.fading);
      o.fading = -1;
      --fading_;
      retire(k);
    }
  }
}

}  // namespace chladni::runtime
