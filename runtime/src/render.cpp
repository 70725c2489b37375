#include "chladni/runtime/render.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/runtime/scene_objects.hpp"
#include "chladni/runtime/scene_player.hpp"
#include "chladni/runtime/shaker_bank.hpp"

namespace chladni::runtime {
namespace {

// Surface points each shaken object's particles move between.
constexpr std::size_t kShakeContacts = 8;

bool same_voice(const ShakeEvent& a, const ShakeEvent& b) {
  return a.object == b.object && a.instrument == b.instrument &&
         a.resonate_object == b.resonate_object && a.particles == b.particles &&
         a.impulse == b.impulse;
}

// The voice of a shake event: the object's modes driven by the instrument's particles, or the
// instrument's own resonances.
ShakerVoice shake_voice(const ShakeEvent& ev, const ObjectModes& obj, double fs, uint64_t seed) {
  try {
    const PhisemPreset& preset = phisem_preset(ev.instrument);
    if (!ev.resonate_object) return instrument_voice(preset, fs, ev.particles);
    if (obj.model && obj.model->has_geometry())
      return object_voice(preset, obj, fs, ev.impulse, kShakeContacts, seed, ev.particles);
    // Inline modes carry their pressure per N*s; a model without geometry its 1 / omega_d.
    ShakerVoice v;
    v.name = preset.name;
    v.excitation = phisem_params(preset, fs, ev.particles);
    for (std::size_t i = 0; i < obj.modes.size(); ++i) {
      const ModeSpec& m = obj.modes[i];
      const double per_ns = obj.inline_modes ? (*obj.inline_modes)[i].amplitude
                            : m.omega_d > 0  ? 1.0 / m.omega_d
                                             : 0.0;
      v.resonances.push_back(
          {m.omega_d, m.decay, {static_cast<float>(per_ns * ev.impulse), 0.0f}, m.gain, 0, 1});
    }
    return v;
  } catch (const InputError& e) {
    throw InputError(ev.json_path + ": " + e.what());
  }
}

// When the timeline's last sound starts: the last impact, or the last shake plus the time its
// voices take to run out of energy and ring down to -100 dB.
double last_event_time(const Scene& scene, const SceneShakers& shakers,
                       const RenderOptions& options, double fs) {
  double last = scene.events.empty() ? 0.0 : scene.events.back().time;
  if (scene.shakes.empty()) return last;
  double ring = 0;
  for (const ShakerVoice& v : shakers.voices) {
    const PhisemParams& p = v.excitation;
    double slowest = 1e9;
    for (const ShakerResonance& r : v.resonances)
      slowest = std::min(slowest, std::max(r.decay, 1e-3));
    const double energy_s = p.system_decay < 1
                                ? std::log(kPhisemMinEnergy) / std::log(p.system_decay) / fs
                                : options.max_tail;
    ring = std::max(ring, energy_s + std::log(1e5) / slowest);
  }
  return std::max(last, scene.shakes.back().time + std::min(ring, options.max_tail));
}

// A move event changes what it names; the rest of the pose stays.
void apply_move(ScenePlayer& player, const MoveEvent& mv) {
  if (mv.object) {
    const std::size_t k = *mv.object;
    player.move(k, mv.position.value_or(player.position(k)),
                mv.orientation.value_or(player.orientation(k)));
  } else {
    Listener l = player.listener();
    if (mv.position) l.position = *mv.position;
    if (mv.forward) l.forward = *mv.forward;
    if (mv.up) l.up = *mv.up;
    player.set_listener(l);
  }
}

}  // namespace

SceneShakers scene_shakers(const Scene& scene, const std::vector<ObjectModes>& objects,
                           uint64_t seed) {
  SceneShakers out;
  for (std::size_t e = 0; e < scene.shakes.size(); ++e) {
    const ShakeEvent& ev = scene.shakes[e];
    int v = 0;
    while (v < static_cast<int>(out.first_event.size()) &&
           !same_voice(scene.shakes[out.first_event[v]], ev))
      ++v;
    if (v == static_cast<int>(out.first_event.size())) {
      out.first_event.push_back(e);
      out.voices.push_back(shake_voice(ev, objects.at(ev.object), scene.sample_rate, seed + v));
      out.slots += static_cast<uint32_t>(out.voices.back().resonances.size());
    }
    out.voice.push_back(v);
  }
  return out;
}

namespace {

PlayerOptions player_options(const Scene& scene, std::size_t objects,
                             const RenderOptions& options) {
  PlayerOptions po;
  po.sample_rate = scene.sample_rate;
  po.gain = scene.gain;
  po.synth = options.synth;
  po.synth.sample_rate = scene.sample_rate;
  po.synth.max_voices = std::max<uint32_t>(po.synth.max_voices, static_cast<uint32_t>(objects));
  po.gain_device = options.gain_device;
  po.gpu_gain_modes = options.gpu_gain_modes;
  po.map_gain_modes = options.map_gain_modes;
  return po;
}

// The shake events' voices take the filterbank's slots above the synth's budget (which shrinks
// to make room). Null without shakes.
std::unique_ptr<ShakerBank> make_shaker_bank(Filterbank& fb, const SceneShakers& shakers,
                                             const RenderOptions& options, PlayerOptions& po) {
  if (shakers.first_event.empty()) return nullptr;
  if (fb.capacity() <= shakers.slots)
    throw InternalError("render: the filterbank has no room for the scene's shakers");
  const uint32_t room = fb.capacity() - shakers.slots;
  po.synth.max_modes = po.synth.max_modes ? std::min(po.synth.max_modes, room) : room;
  po.synth.reserved_end = po.synth.max_modes + shakers.slots;
  ShakerBankOptions bo;
  bo.sample_rate = po.sample_rate;
  bo.first_slot = po.synth.max_modes;
  bo.max_voices = static_cast<uint32_t>(shakers.first_event.size());
  bo.seed = options.seed;
  bo.excitation = fb.device() ? ExcitationBackend::Gpu : ExcitationBackend::Cpu;
  auto bank = std::make_unique<ShakerBank>(fb, bo);
  for (const ShakerVoice& v : shakers.voices) bank->add_voice(v);
  return bank;
}

// A scene's timeline played through a ScenePlayer and its shakers, block by block.
class Timeline {
 public:
  Timeline(const Scene& scene, const std::vector<ObjectModes>& objects, Filterbank& fb,
           const RenderOptions& options)
      : scene_(scene),
        fs_(scene.sample_rate),
        shakers_(scene_shakers(scene, objects, options.seed)),
        po_(player_options(scene, objects.size(), options)),
        bank_(make_shaker_bank(fb, shakers_, options, po_)),
        player_(fb, po_),
        objects_(objects) {
    for (std::size_t k = 0; k < objects.size(); ++k)
      player_.add_object(objects[k], scene.objects[k].position, scene.objects[k].orientation,
                         scene.objects[k].gain);
    player_.set_listener(scene.listener);
    player_.finish_objects();
    if (player_.update_gains()) shaker_gains();
    last_event_ = last_event_time(scene, shakers_, options, fs_);
  }

  double last_event() const { return last_event_; }
  ScenePlayer& player() { return player_; }
  bool done() const {
    return next_ == scene_.events.size() && next_move_ == scene_.moves.size() &&
           next_shake_ == scene_.shakes.size();
  }

  // Plays the events due in [t, t + frames) and renders; returns the frames rendered (a block
  // ends before a move that falls inside it, or before an impact the excitation list cannot
  // take yet).
  uint32_t render(uint64_t t, uint32_t frames, float* out) {
    frames = apply_moves(t, frames);
    if (player_.update_gains()) shaker_gains();
    frames = apply_impacts(t, frames);
    DriveInput drive;
    if (bank_) {
      for (; next_shake_ < scene_.shakes.size(); ++next_shake_) {
        const ShakeEvent& ev = scene_.shakes[next_shake_];
        const uint64_t at = first_sample(ev.time, fs_);
        if (at >= t + frames) break;
        bank_->shake(shakers_.voice[next_shake_], static_cast<float>(ev.energy),
                     static_cast<uint32_t>(at - t));
      }
      drive = bank_->prepare(frames);
    }
    player_.render(frames, out, drive);
    if (bank_) bank_->finish(frames);
    return frames;
  }

 private:
  // Moves take effect at their first sample: apply those due, end the block before the next.
  uint32_t apply_moves(uint64_t t, uint32_t frames) {
    for (; next_move_ < scene_.moves.size(); ++next_move_) {
      const MoveEvent& mv = scene_.moves[next_move_];
      const uint64_t at = first_sample(mv.time, fs_);
      if (at > t) return at < t + frames ? static_cast<uint32_t>(at - t) : frames;
      apply_move(player_, mv);
    }
    return frames;
  }

  // Impacts whose first sample falls in [t, t + frames).
  uint32_t apply_impacts(uint64_t t, uint32_t frames) {
    const Synth& synth = player_.synth();
    for (; next_ < scene_.events.size(); ++next_) {
      const ImpactEvent& ev = scene_.events[next_];
      const uint64_t at = first_sample(ev.time, fs_);
      if (at >= t + frames) break;
      if (synth.pending_excitations() + objects_[ev.object].modes.size() >
          synth.excitation_capacity())
        return at > t ? static_cast<uint32_t>(at - t) : frames;  // render up to it, then strike
      player_.impact(ev.object, ev, ev.time * fs_ - static_cast<double>(t));
    }
    return frames;
  }

  // Shakers on an object: its mode gains, or plain spreading for an instrument's own.
  void shaker_gains() {
    for (std::size_t v = 0; bank_ && v < shakers_.first_event.size(); ++v) {
      const ShakeEvent& ev = scene_.shakes[shakers_.first_event[v]];
      const float* pan = player_.pan(ev.object);
      if (ev.resonate_object) {
        bank_->set_gains(static_cast<int>(v), player_.gains(ev.object), pan[0], pan[1]);
      } else {
        flat_.assign(shakers_.voices[v].resonances.size(),
                     static_cast<float>(player_.spreading(ev.object)));
        bank_->set_gains(static_cast<int>(v), flat_, pan[0], pan[1]);
      }
    }
  }

  const Scene& scene_;
  double fs_;
  SceneShakers shakers_;
  PlayerOptions po_;
  std::unique_ptr<ShakerBank> bank_;
  ScenePlayer player_;
  const std::vector<ObjectModes>& objects_;
  std::vector<float> flat_;
  std::size_t next_ = 0, next_move_ = 0, next_shake_ = 0;
  double last_event_ = 0;
};

}  // namespace

AudioBuffer render_scene(const Scene& scene, const std::vector<ObjectModes>& objects,
                         Filterbank& fb, const RenderOptions& options, RenderReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  if (objects.size() != scene.objects.size()) throw InternalError("render: object count mismatch");
  if (fb.channels() != scene.channels) throw InternalError("render: channel count mismatch");
  const double fs = scene.sample_rate;
  const uint32_t block = std::min(options.block, fb.max_frames());
  if (block == 0) throw InputError("block size must be > 0");
  Timeline timeline(scene, objects, fb, options);
  const uint64_t limit =
      first_sample(scene.duration ? *scene.duration : timeline.last_event() + options.max_tail, fs);
  AudioBuffer audio;
  audio.sample_rate = scene.sample_rate;
  audio.channels = scene.channels;
  audio.samples.reserve(static_cast<std::size_t>(std::min<uint64_t>(limit, 1ull << 28)) *
                        scene.channels);
  std::vector<float> buf(static_cast<std::size_t>(block) * scene.channels);
  const Synth& synth = timeline.player().synth();
  RenderReport rep;
  for (uint64_t t = 0; t < limit;) {
    const uint32_t frames =
        timeline.render(t, static_cast<uint32_t>(std::min<uint64_t>(block, limit - t)), buf.data());
    rep.max_active_modes = std::max(rep.max_active_modes, synth.active_modes());
    audio.samples.insert(audio.samples.end(), buf.begin(), buf.begin() + frames * scene.channels);
    t += frames;
    if (options.progress && (t / block) % 256 == 0) options.progress(double(t) / double(limit));
    // Without a duration, stop once every event is played and everything has rung out.
    if (!scene.duration && timeline.done() && synth.active_modes() == 0 &&
        double(t) / fs >= timeline.last_event())
      break;
  }
  for (float x : audio.samples) rep.peak = std::max(rep.peak, double(std::abs(x)));
  rep.frames = audio.frames();
  rep.stats = synth.stats();
  rep.gain_updates = timeline.player().gain_updates();
  rep.gain_seconds = timeline.player().gain_seconds();
  rep.gain_backend = timeline.player().gain_backend();
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (report) *report = rep;
  return audio;
}

}  // namespace chladni::runtime
