#pragma once
// Scene objects made playable: the one place that loads a soundbank for a sample rate (keeping
// the modes below Nyquist, refusing a bank with none), builds an analytic bar with its damping,
// or wraps inline modes; and the one rule for a mode's gain at the listener.
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "chladni/core/modal_model.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/runtime/scene/render.hpp"

namespace chladni::runtime {

struct PlayableObject {
  std::unique_ptr<ModalModel> model;  ///< banks and bars; null for inline modes
  ObjectModes modes;                  ///< points into `model` (or into the scene's inline modes)
  std::string summary;                ///< one line for the user: source, mode count, lowest Hz
};

/// `bank`'s modes that `sample_rate` can play (below Nyquist). InputError naming `what` when
/// none is left; `dropped` (optional) receives how many were cut.
ModalModel playable_model(const Soundbank& bank, const std::string& name, double sample_rate,
                          const std::string& what, std::size_t* dropped = nullptr);

/// One scene object; errors name its JSON path (and the soundbank file). Inline modes are
/// referenced, not copied: `object` must outlive the result.
PlayableObject resolve_object(const SceneObject& object, double sample_rate);
std::vector<PlayableObject> resolve_objects(const Scene& scene);

/// The gain of each mode at the listener: scale * transfer[i] where the object's transfer fit is
/// usable (`transfer` may be empty: none), else the mode's compact-source gain times `spread`
/// (the 1/r spreading and any scale).
void listener_mode_gains(const ObjectModes& object, std::span<const float> transfer, double scale,
                         double spread, std::span<float> out);

/// Sets each mode's `gain` in `object` (built from `model`) to its pressure at a listener at
/// `listener` (m, object frame) per unit modal acceleration, once: by the model's transfer when
/// it has one, else by the compact-source gain with 1/r spreading (r at least 0.1 m).
void gains_at_listener(const ModalModel& model, ObjectModes& object, const Vec3& listener);

/// The first sample at or after `time` seconds: the one time-to-sample rule of the runtime.
inline uint64_t first_sample(double time, double sample_rate) {
  return static_cast<uint64_t>(std::ceil(time * sample_rate));
}

}  // namespace chladni::runtime
