#include "chladni/runtime/scene/render.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/runtime/scene/scene_timeline.hpp"

namespace chladni::runtime {
AudioBuffer render_scene(const Scene& scene, const std::vector<ObjectModes>& objects,
                         Filterbank& fb, const RenderOptions& options, RenderReport* report) {
  return render_scene(scene, objects, scene_shakers(scene, objects, options.seed), fb, options,
                      report);
}

AudioBuffer render_scene(const Scene& scene, const std::vector<ObjectModes>& objects,
                         const SceneShakers& shakers, Filterbank& fb, const RenderOptions& options,
                         RenderReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  const uint32_t block = std::min(options.block, fb.max_frames());
  if (block == 0) throw InputError("block size must be > 0");
  SceneTimeline timeline(scene, objects, shakers, fb, options);
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
