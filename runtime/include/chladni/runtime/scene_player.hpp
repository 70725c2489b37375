#pragma once
// A live scene: sounding objects placed in the world and a listener. The one place that turns
// objects into voices, poses into per-mode listener gains (transfer where its fit is usable,
// else the compact-source gain over distance; scene_objects.hpp) and constant-power pan, and
// impacts into strikes with their contact force. render_scene() drives one from a Scene's
// timeline; an engine drives one directly.
//
// Threading: add_object() allocates (a control thread, never during render()); move(),
// set_listener(), impact() and render() do not allocate once the objects are added.
#include <chrono>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "chladni/core/scene.hpp"
#include "chladni/runtime/render.hpp"
#include "chladni/runtime/synth.hpp"
#include "chladni/runtime/thread_pool.hpp"
#include "chladni/runtime/transfer_gains.hpp"

namespace chladni::gpu {
class Context;
}

namespace chladni::runtime {

struct PlayerOptions {
  double sample_rate = 48000;
  double gain = 1.0;  ///< scales every object
  SynthOptions synth;
  /// Listener gains on this device once the objects with transfer have gpu_gain_modes modes
  /// (null: always on the CPU); far-field maps on the CPU from map_gain_modes modes.
  std::shared_ptr<gpu::Context> gain_device;
  std::size_t gpu_gain_modes = 20000;
  std::size_t map_gain_modes = 4096;
};

class ScenePlayer {
 public:
  /// The player's voices take the synth's budget of `filterbank` (options.synth).
  ScenePlayer(Filterbank& filterbank, const PlayerOptions& options);
  ~ScenePlayer();

  /// Adds an object (its modes, pose and gain); returns its index. Objects sharing a Transfer
  /// share its coefficients and maps. Control thread.
  std::size_t add_object(const ObjectModes& modes, const Vec3& position, const Quat& orientation,
                         double gain = 1.0);
  /// Silences an object at once (its slots are freed) and ignores it from then on.
  void remove(std::size_t object);
  bool active(std::size_t object) const { return objects_.at(object).voice >= 0; }
  /// Prepares the listener-gain tables for the objects added so far (maps, device buffers);
  /// done by the first update otherwise. Control thread.
  void finish_objects();

  void move(std::size_t object, const Vec3& position, const Quat& orientation);
  void set_listener(const Listener& listener);
  /// Strikes `object`: the event's point or vertex, direction, impulse and contact time, from
  /// fractional sample `start` of the next render (-1 < start < max_frames()).
  void impact(std::size_t object, const ImpactEvent& event, double start);

  /// Recomputes the listener gains when a pose changed since the last update; true if it did.
  bool update_gains();
  /// Renders `frames` interleaved frames (updating gains first if needed).
  void render(uint32_t frames, float* out, const DriveInput& drive = {});

  /// The last update's per-mode gains and pan of an object, and its distance spreading (gain /
  /// distance): for other voices placed at the object (shakers).
  std::span<const float> gains(std::size_t object) const { return objects_[object].gains; }
  const float* pan(std::size_t object) const { return objects_[object].pan; }
  double spreading(std::size_t object) const { return objects_[object].spread; }

  const Vec3& position(std::size_t object) const { return objects_.at(object).position; }
  const Quat& orientation(std::size_t object) const { return objects_.at(object).orientation; }
  const Listener& listener() const { return listener_; }
  Synth& synth() { return synth_; }
  const Synth& synth() const { return synth_; }
  std::size_t object_count() const { return objects_.size(); }
  std::size_t mode_count(std::size_t object) const { return objects_.at(object).gains.size(); }
  /// Surface points an impact may name by vertex (0 without geometry).
  std::size_t points(std::size_t object) const {
    const ObjectModes& m = objects_.at(object).modes;
    return m.model && m.model->has_geometry() ? m.model->points.size() : 0;
  }
  uint64_t gain_updates() const { return gain_updates_; }
  double gain_seconds() const { return gain_seconds_; }
  /// "cpu", "gpu" or "" when no object has transfer.
  std::string gain_backend() const;

 private:
  struct Object {
    ObjectModes modes;
    Synth::VoiceId voice = -1;
    Vec3 position{0, 0, 0};
    Quat orientation{1, 0, 0, 0};
    double gain = 1;
    int table = -1;  // index in table_.objects
    std::vector<float> gains;
    std::vector<std::complex<float>> coupling;
    float pan[2] = {1, 1};
    double spread = 1;
  };
  void apply_gains(Object& object);

  Filterbank& fb_;
  PlayerOptions opt_;
  Synth synth_;
  std::vector<Object> objects_;
  Listener listener_;
  bool dirty_ = true;
  // Listener gains from transfer.
  TransferTable table_;
  ListenerFrame frame_;
  std::vector<Vec3> listener_local_;
  std::vector<float> table_gains_;
  std::unique_ptr<ThreadPool> pool_;
  std::unique_ptr<GpuTransferGains> gpu_gains_;
  bool tables_ready_ = false;
  uint64_t gain_updates_ = 0;
  double gain_seconds_ = 0;
};

}  // namespace chladni::runtime
