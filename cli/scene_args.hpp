#pragma once
// The options render and play share, and the scene settings they become.
#include <cstdint>
#include <string>

#include "chladni/core/scene.hpp"
#include "chladni/runtime/scene/prepare_scene.hpp"

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

/// --backend, --block, --gain-ramp, --threads, --isa, --max-modes, --retire-db, -q.
void add_scene_options(CLI::App& cmd, SceneArgs& args);

/// The scene prepared for `args`, one line per object unless quiet.
runtime::PreparedScene prepare(const Scene& scene, const SceneArgs& args);

}  // namespace chladni::cli
