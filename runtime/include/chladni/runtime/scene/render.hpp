#pragma once
// Offline rendering of a scene: one voice per object, impacts placed sample-accurately, gains
// from the listener's pose: per-mode |p(listener)| from acoustic transfer where the object has it,
// else the mode's compact-source gain with 1/r spreading; constant-power pan in stereo. Gains are
// recomputed whenever the listener or an object moves.
#include <functional>
#include <memory>
#include <vector>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/modal_model.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/modal/object_modes.hpp"
#include "chladni/runtime/modal/synth.hpp"
#include "chladni/runtime/scene/scene_shakers.hpp"

namespace chladni::gpu {
class Context;
}

namespace chladni::runtime {

struct RenderOptions {
  uint32_t block = 256;    ///< frames per filterbank call
  double max_tail = 60.0;  ///< s after the last event when the scene gives no duration
  SynthOptions synth;      ///< sample_rate is taken from the scene
  std::function<void(double fraction)> progress;  ///< optional
  /// Evaluate transfer gains on this device when the scene has at least gpu_gain_modes modes
  /// with transfer (null: always on the CPU).
  std::shared_ptr<gpu::Context> gain_device;
  std::size_t gpu_gain_modes = 20000;
  /// On the CPU, listener gains come from far-field maps (gain_map.hpp) when the scene has at
  /// least this many modes with transfer: their build pays off once many modes are updated.
  std::size_t map_gain_modes = 4096;
  uint64_t seed = 1;  ///< shake events' random streams
};

struct RenderReport {
  uint64_t frames = 0;
  double peak = 0;
  SynthStats stats;
  uint32_t max_active_modes = 0;
  double seconds = 0;         ///< wall time
  uint64_t gain_updates = 0;  ///< listener-gain recomputations (start and each move)
  double gain_seconds = 0;    ///< wall time spent in them
  std::string gain_backend;   ///< "cpu", "gpu" or "" without transfer
};

/// Renders the scene; `objects[i]` describes scene.objects[i] and `shakers` its shake events'
/// voices (scene_shakers; the overload without builds them). The filterbank's channel count must
/// match the scene's, and its capacity hold the options' max_modes plus the shakers' slots.
/// prepare_scene.hpp sizes and builds all of it once.
AudioBuffer render_scene(const Scene& scene, const std::vector<ObjectModes>& objects,
                         const SceneShakers& shakers, Filterbank& filterbank,
                         const RenderOptions& options, RenderReport* report = nullptr);
AudioBuffer render_scene(const Scene& scene, const std::vector<ObjectModes>& objects,
                         Filterbank& filterbank, const RenderOptions& options,
                         RenderReport* report = nullptr);

}  // namespace chladni::runtime
