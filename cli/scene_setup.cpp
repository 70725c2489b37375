#include "scene_setup.hpp"

#include <algorithm>
#include <cstdio>

#include "backend.hpp"
#include "chladni/gpu/context.hpp"
#include "commands.hpp"

namespace chladni::cli {

SceneSetup setup_scene(const Scene& scene, const SceneArgs& a) {
  SceneSetup s;
  s.playable = runtime::resolve_objects(scene);
  for (std::size_t k = 0; k < s.playable.size(); ++k) {
    s.objects.push_back(s.playable[k].modes);
    if (!a.quiet)
      std::printf("  %-12s %s\n", scene.objects[k].name.c_str(), s.playable[k].summary.c_str());
  }
  std::size_t total_modes = 0, transfer_modes = 0;
  for (const auto& o : s.objects) {
    total_modes += o.modes.size();
    transfer_modes += o.transfer ? o.modes.size() : 0;
  }
  BackendRequest req;
  req.backend = a.backend;
  req.channels = scene.channels;
  req.threads = a.threads;
  req.isa = a.isa;
  const uint32_t budget =
      a.max_modes ? a.max_modes
                  : static_cast<uint32_t>(std::clamp<std::size_t>(total_modes, 1024, 1u << 20));
  // Shake events' voices sit in slots of their own above the impacts' budget.
  const runtime::SceneShakers shakers = runtime::scene_shakers(scene, s.objects);
  req.capacity = budget + shakers.slots;
  req.max_streams = static_cast<uint32_t>(shakers.first_event.size());
  req.max_frames = std::max<uint32_t>(a.block, 256);
  req.gain_ramp = a.gain_ramp;
  req.pipelined = a.live;
  s.fb = make_filterbank(req);
  s.options.block = a.block;
  s.options.synth.retire_db = a.retire_db;
  s.options.synth.max_modes = budget;
  if (a.backend == "gpu" && transfer_modes >= s.options.gpu_gain_modes) {
    try {
      s.options.gain_device = std::make_shared<gpu::Context>();
    } catch (const gpu::NoDeviceError&) {
      // the filterbank already warned; gains stay on the CPU
    }
  }
  return s;
}

void add_scene_options(CLI::App& cmd, SceneArgs& a) {
  cmd.add_option("--backend", a.backend, "Filterbank: cpu or gpu (gpu falls back to cpu)")
      ->capture_default_str();
  cmd.add_option("--block", a.block, "Frames per filterbank call")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  cmd.add_option("--gain-ramp", a.gain_ramp,
                 "Samples over which listener and pose changes ramp the gains (0: at once)")
      ->check(CLI::Range(0, 65536))
      ->capture_default_str();
  cmd.add_option("--threads", a.threads, "CPU threads (0: all)")
      ->check(thread_count())
      ->capture_default_str();
  cmd.add_option("--isa", a.isa, "CPU instruction set: auto, scalar, avx2, avx512")
      ->capture_default_str();
  cmd.add_option("--max-modes", a.max_modes, "Resident mode budget (0: all modes of the scene)")
      ->check(CLI::Range(0, 1 << 24));
  cmd.add_option("--retire-db", a.retire_db, "Retire modes this far below their peak (dB)")
      ->check(finite_in(-400, 0))
      ->capture_default_str();
  cmd.add_flag("-q,--quiet", a.quiet, "Print nothing but errors");
}

}  // namespace chladni::cli
