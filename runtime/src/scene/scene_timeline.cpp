#include "chladni/runtime/scene/scene_timeline.hpp"

#include <algorithm>
#include <cmath>

#include "chladni/core/error.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"

namespace chladni::runtime {
namespace {

// Seconds the slowest of a body's modes takes to ring down by 100 dB.
double ring_seconds(const ObjectModes& o) {
  double slowest = 1e9;
  for (const ModeSpec& m : o.modes) slowest = std::min(slowest, std::max(m.decay, 1e-3));
  return std::log(1e5) / slowest;
}

// When the timeline's last sound starts: the last impact, the last contact's end plus its
// bodies' ring-down (the synth does not see their slots), or the last shake plus the time its
// voices take to run out of energy and ring down to -100 dB.
double last_event_time(const Scene& scene, const std::vector<ObjectModes>& objects,
                       const SceneShakers& shakers, const RenderOptions& options, double fs) {
  double last = scene.events.empty() ? 0.0 : scene.events.back().time;
  for (const ContactEvent& c : scene.contacts) {
    double ring = ring_seconds(objects[c.object]);
    if (c.other) ring = std::max(ring, ring_seconds(objects[*c.other]));
    last = std::max(last, c.end_time() + std::min(ring, options.max_tail));
  }
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

PlayerOptions player_options(const Scene& scene, const std::vector<ObjectModes>& objects,
                             const SceneShakers& shakers, const RenderOptions& options,
                             uint32_t max_frames) {
  PlayerOptions po;
  po.sample_rate = scene.sample_rate;
  po.gain = scene.gain;
  po.synth = options.synth;
  po.synth.sample_rate = scene.sample_rate;
  po.synth.max_voices =
      std::max<uint32_t>(po.synth.max_voices, static_cast<uint32_t>(objects.size()));
  po.gain_device = options.gain_device;
  po.gpu_gain_modes = options.gpu_gain_modes;
  po.map_gain_modes = options.map_gain_modes;
  po.shaker_slots = shakers.slots;
  po.max_shakers = static_cast<uint32_t>(shakers.voices.size());
  po.seed = options.seed;
  po.max_contacts = static_cast<uint32_t>(scene.contacts.size());
  po.contact_slots = contact_slots(scene, objects);
  po.contact_points = contact_points_per_block(scene, max_frames);
  return po;
}

}  // namespace

SceneTimeline::SceneTimeline(const Scene& scene, const std::vector<ObjectModes>& objects,
                             Filterbank& fb, const RenderOptions& options)
    : SceneTimeline(scene, objects, scene_shakers(scene, objects, options.seed), fb, options) {}

SceneTimeline::SceneTimeline(const Scene& scene, PreparedScene& p)
    : SceneTimeline(scene, p.objects, p.shakers, *p.filterbank, p.options) {}

SceneTimeline::SceneTimeline(const Scene& scene, const std::vector<ObjectModes>& objects,
                             SceneShakers shakers, Filterbank& fb, const RenderOptions& options)
    : scene_(scene),
      fs_(scene.sample_rate),
      shakers_(std::move(shakers)),
      contacts_(scene_contacts(scene, objects)),
      contact_next_(contacts_.size(), 0),
      player_(fb, player_options(scene, objects, shakers_, options, fb.max_frames())),
      objects_(objects),
      max_frames_(fb.max_frames()) {
  if (objects.size() != scene.objects.size()) throw InternalError("render: object count mismatch");
  if (fb.channels() != scene.channels) throw InternalError("render: channel count mismatch");
  for (std::size_t k = 0; k < objects.size(); ++k)
    player_.add_object(objects[k], scene.objects[k].position, scene.objects[k].orientation,
                       scene.objects[k].gain);
  player_.set_listener(scene.listener);
  for (std::size_t v = 0; v < shakers_.voices.size(); ++v) {
    const ShakeEvent& ev = scene.shakes[shakers_.first_event[v]];
    player_.add_shaker(ev.object, shakers_.voices[v], ev.resonate_object);
  }
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    const ContactEvent& ev = scene.contacts[c];
    player_.add_contact(ev.object, ev.other ? long(*ev.other) : -1, contacts_[c].roughness,
                        options.seed + 0x1000 + c, ev.json_path);
  }
  player_.finish_objects();
  player_.update_gains();
  last_event_ = last_event_time(scene, objects, shakers_, options, fs_);
  end_ = first_sample(scene.duration ? *scene.duration : last_event_ + options.max_tail, fs_);
}

SceneTimeline::~SceneTimeline() = default;

bool SceneTimeline::rung_out() const {
  return next_ == scene_.events.size() && next_move_ == scene_.moves.size() &&
         next_shake_ == scene_.shakes.size() && player_.synth().active_modes() == 0 &&
         double(t_) / fs_ >= last_event_;
}

uint32_t SceneTimeline::render_step(uint32_t frames, float* out) {
  frames = apply_moves(std::min(frames, max_frames_));
  frames = apply_impacts(frames);
  for (; next_shake_ < scene_.shakes.size(); ++next_shake_) {
    const ShakeEvent& ev = scene_.shakes[next_shake_];
    const uint64_t at = first_sample(ev.time, fs_);
    if (at >= t_ + frames) break;
    player_.shake(shakers_.voice[next_shake_], static_cast<float>(ev.energy),
                  static_cast<uint32_t>(at - t_));
  }
  push_contacts(frames);
  player_.render(frames, out);
  t_ += frames;
  return frames;
}

void SceneTimeline::render(uint32_t frames, float* out) {
  while (frames > 0) {
    const uint32_t n = render_step(frames, out);
    out += static_cast<std::size_t>(n) * scene_.channels;
    frames -= n;
  }
}

// Queues each contact's points up to the first past this block (the interpolation needs it),
// and ends a contact once its last point is queued.
void SceneTimeline::push_contacts(uint32_t frames) {
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    const std::vector<ContactPoint>& pts = contacts_[c].points;
    std::size_t& next = contact_next_[c];
    while (next < pts.size() && (next == 0 || pts[next - 1].sample < t_ + frames)) {
      if (!player_.push_contact(int(c), pts[next])) break;
      if (++next == pts.size()) player_.end_contact(int(c), pts.back().sample);
    }
  }
}

// Moves take effect at their first sample: apply those due, end the step before the next.
uint32_t SceneTimeline::apply_moves(uint32_t frames) {
  for (; next_move_ < scene_.moves.size(); ++next_move_) {
    const MoveEvent& mv = scene_.moves[next_move_];
    const uint64_t at = first_sample(mv.time, fs_);
    if (at > t_) return at < t_ + frames ? static_cast<uint32_t>(at - t_) : frames;
    apply_move(player_, mv);
  }
  return frames;
}

// Impacts whose first sample falls in [t, t + frames).
uint32_t SceneTimeline::apply_impacts(uint32_t frames) {
  const Synth& synth = player_.synth();
  for (; next_ < scene_.events.size(); ++next_) {
    const ImpactEvent& ev = scene_.events[next_];
    const uint64_t at = first_sample(ev.time, fs_);
    if (at >= t_ + frames) break;
    if (synth.pending_excitations() + objects_[ev.object].modes.size() >
        synth.excitation_capacity())
      return at > t_ ? static_cast<uint32_t>(at - t_) : frames;  // up to it, then strike
    player_.impact(ev.object, ev, ev.time * fs_ - static_cast<double>(t_));
  }
  return frames;
}

}  // namespace chladni::runtime
