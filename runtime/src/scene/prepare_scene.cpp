#include "chladni/runtime/scene/prepare_scene.hpp"

#include <algorithm>

#include "chladni/gpu/context.hpp"
#include "chladni/runtime/scene/scene_contacts.hpp"
#include "chladni/runtime/scene/scene_timeline.hpp"

namespace chladni::runtime {

PreparedScene prepare_scene(const Scene& scene, const SceneSettings& s) {
  PreparedScene p;
  p.playable = resolve_objects(scene);
  std::size_t total_modes = 0, transfer_modes = 0;
  for (const PlayableObject& o : p.playable) {
    p.objects.push_back(o.modes);
    total_modes += o.modes.modes.size();
    transfer_modes += o.modes.transfer ? o.modes.modes.size() : 0;
  }
  p.shakers = scene_shakers(scene, p.objects, s.seed);
  scene_contacts(scene, p.objects);  // refuses what cannot play before anything is sized
  const uint32_t budget =
      s.max_modes ? s.max_modes
                  : static_cast<uint32_t>(std::clamp<std::size_t>(total_modes, 1024, 1u << 20));
  FilterbankRequest r = s.filterbank;
  r.channels = scene.channels;
  // Shake voices and contacts sit in slots above the impacts' budget.
  r.capacity = budget + p.shakers.slots + contact_slots(scene, p.objects);
  r.max_streams = static_cast<uint32_t>(p.shakers.voices.size() + scene.contacts.size());
  r.max_frames = std::max<uint32_t>(s.block, 256);
  p.filterbank = make_filterbank(r);
  p.options.block = s.block;
  p.options.seed = s.seed;
  p.options.synth.retire_db = s.retire_db;
  p.options.synth.max_modes = budget;
  // Listener gains go to a device of their own where the filterbank runs on one and enough modes
  // have transfer to pay for it.
  const bool on_gpu = p.filterbank->name().starts_with("gpu");
  if (on_gpu && transfer_modes >= p.options.gpu_gain_modes)
    p.options.gain_device = gpu::open_device(gpu::DeviceChoice::Gpu);
  return p;
}

AudioBuffer render_scene(const Scene& scene, PreparedScene& p, RenderReport* report) {
  return render_scene(scene, p.objects, p.shakers, *p.filterbank, p.options, report);
}

}  // namespace chladni::runtime
