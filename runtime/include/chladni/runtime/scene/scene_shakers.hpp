#pragma once
// The PhISEM voices a scene's shake events play: each built once, from the event's instrument
// and, where it resonates the object, the object's modes.
#include <cstdint>
#include <vector>

#include "chladni/core/scene.hpp"
#include "chladni/runtime/modal/object_modes.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"

namespace chladni::runtime {

/// The voice of a shake: `object`'s modes driven by the instrument's particles (resonate_object;
/// `seed` draws its contact points), or the instrument's own resonances. InputError, prefixed
/// with the event's JSON path, for an unknown instrument or bad parameters.
ShakerVoice shake_voice(const ShakeEvent& event, const ObjectModes& object, double sample_rate,
                        uint64_t seed);

/// The shaker voices a scene's shake events need: one per (object, instrument, resonance choice,
/// particle count, impulse), voice v seeded with seed + v; `voice[e]` is scene.shakes[e]'s.
struct SceneShakers {
  std::vector<std::size_t> first_event;  ///< per voice: the event that defines it
  std::vector<ShakerVoice> voices;       ///< per voice
  std::vector<int> voice;                ///< per shake event
  uint32_t slots = 0;                    ///< filterbank slots of all the voices
};

/// Validates the instruments (InputError naming the event's JSON path).
SceneShakers scene_shakers(const Scene& scene, const std::vector<ObjectModes>& objects,
                           uint64_t seed = 1);

}  // namespace chladni::runtime
