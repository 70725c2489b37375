#pragma once
// What render and play share: a loaded scene's objects resolved, a filterbank sized for them
// and their shakes, and the options of the timeline that plays them.
#include <memory>
#include <string>
#include <vector>

#include "chladni/core/scene.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"

namespace CLI {
class App;
}

namespace chladni::cli {

struct SceneArgs {
  std::string backend = "cpu", isa = "auto";
  int threads = 0;
  uint32_t block = 256, max_modes = 0, gain_ramp = 256;
  double retire_db = -100;
  bool quiet = false;
  bool live = false;  ///< a live stream: the GPU filterbank pipelines its blocks
};

struct SceneSetup {
  std::vector<runtime::PlayableObject> playable;  ///< owns what `objects` points into
  std::vector<runtime::ObjectModes> objects;
  std::unique_ptr<runtime::Filterbank> fb;
  runtime::RenderOptions options;
};

/// Resolves the scene's objects (one line each unless quiet) and builds the filterbank.
SceneSetup setup_scene(const Scene& scene, const SceneArgs& args);

/// The options render and play share: --backend, --block, --gain-ramp, --threads, --isa,
/// --max-modes, --retire-db, -q.
void add_scene_options(CLI::App& cmd, SceneArgs& args);

}  // namespace chladni::cli
