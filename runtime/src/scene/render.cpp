#include "chladni/runtime/scene/render.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "chladni/runtime/scene/scene_timeline.hpp"

namespace chladni::runtime {
namespace {

// Surface points each shaken object's particles move between.
constexpr std::size_t kShakeContacts = 8;

bool same_voice(const ShakeEvent& a, const ShakeEvent& b) {
  return a.object == b.object && a.instrument == b.instrument &&
         a.resonate_object == b.resonate_object && a.particles == b.particles &&
         a.impulse == b.impulse;
}

}  // namespace

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

AudioBuffer render_scene(const Scene& scene, const std::vector<ObjectModes>& objects,
                         Filterbank& fb, const RenderOptions& options, RenderReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  const uint32_t block = std::min(options.block, fb.max_frames());
  if (block == 0) throw InputError("block size must be > 0");
  SceneTimeline timeline(scene, objects, fb, options);
  const uint64_t limit = timeline.end();
  AudioBuffer audio;
  audio.sample_rate = scene.sample_rate;
  audio.channels = scene.channels;
  audio.samples.reserve(static_cast<std::size_t>(std::min<uint64_t>(limit, 1ull << 28)) *
                        scene.channels);
  std::vector<float> buf(static_cast<std::size_t>(block) * scene.channels);
  const Synth& synth = timeline.synth();
  RenderReport rep;
  while (timeline.time() < limit) {
    const uint32_t frames = timeline.render_step(
        static_cast<uint32_t>(std::min<uint64_t>(block, limit - timeline.time())), buf.data());
    rep.max_active_modes = std::max(rep.max_active_modes, synth.active_modes());
    audio.samples.insert(audio.samples.end(), buf.begin(), buf.begin() + frames * scene.channels);
    const uint64_t t = timeline.time();
    if (options.progress && (t / block) % 256 == 0) options.progress(double(t) / double(limit));
    // Without a duration, stop once every event is played and everything has rung out.
    if (!scene.duration && timeline.rung_out()) break;
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
