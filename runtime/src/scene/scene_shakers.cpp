#include "chladni/runtime/scene/scene_shakers.hpp"

#include "chladni/core/error.hpp"

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

}  // namespace chladni::runtime
