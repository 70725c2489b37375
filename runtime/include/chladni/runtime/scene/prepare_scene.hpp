#pragma once
// A scene made ready to play, once, for every path from a scene to sound (chladni render and
// play, the examples, the tests): its objects resolved, its shakers built, and one filterbank
// sized for both. SceneTimeline plays it live; render_scene plays it into a buffer.
#include <cstdint>
#include <memory>
#include <vector>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/runtime/filterbank/make_filterbank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "chladni/runtime/scene/scene_shakers.hpp"

namespace chladni::runtime {

struct SceneSettings {
  /// Backend, threads, isa, gain ramp, pipelining and the fallback warning; the capacity,
  /// channels, streams and frames are sized from the scene.
  FilterbankRequest filterbank;
  uint32_t block = 256;    ///< frames per filterbank call
  uint32_t max_modes = 0;  ///< resident mode budget; 0: the scene's, within [1024, 2^20]
  double retire_db = -100;
  uint64_t seed = 1;  ///< shake events' random streams
};

struct PreparedScene {
  std::vector<PlayableObject> playable;  ///< owns what `objects` points into
  std::vector<ObjectModes> objects;      ///< objects[i] plays scene.objects[i]
  SceneShakers shakers;
  std::unique_ptr<Filterbank> filterbank;
  RenderOptions options;
};

/// Errors name the object's or event's JSON path (and the soundbank file).
PreparedScene prepare_scene(const Scene& scene, const SceneSettings& settings = {});

/// Renders a prepared scene to its end (render.hpp's render_scene, without building anything).
AudioBuffer render_scene(const Scene& scene, PreparedScene& prepared,
                         RenderReport* report = nullptr);

}  // namespace chladni::runtime
