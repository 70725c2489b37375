#pragma once
// A scene's timeline played live: its objects and shakers in a ScenePlayer, and its impacts,
// moves and shakes applied on their samples as the audio is pulled block by block. render_scene()
// pulls it to the end into a buffer; `chladni play` pulls it from an audio device's callback.
#include <memory>
#include <vector>

#include "chladni/core/scene.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "chladni/runtime/scene/prepare_scene.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "chladni/runtime/scene/scene_contacts.hpp"
#include "chladni/runtime/scene/scene_player.hpp"

namespace chladni::runtime {

class SceneTimeline {
 public:
  /// `scene` and `objects` (objects[i] describes scene.objects[i]) must outlive the timeline;
  /// `shakers` are the scene's shake voices (scene_shakers).
  SceneTimeline(const Scene& scene, const std::vector<ObjectModes>& objects, SceneShakers shakers,
                Filterbank& fb, const RenderOptions& options);
  /// Builds the shakers itself.
  SceneTimeline(const Scene& scene, const std::vector<ObjectModes>& objects, Filterbank& fb,
                const RenderOptions& options);
  /// A prepared scene, which must outlive the timeline.
  SceneTimeline(const Scene& scene, PreparedScene& prepared);
  ~SceneTimeline();

  /// Renders up to `frames` (at most the filterbank's max_frames()) interleaved frames, ending
  /// early before a move or where the excitation list is full; returns the frames rendered.
  uint32_t render_step(uint32_t frames, float* out);
  /// Renders exactly `frames` frames (any count), in steps.
  void render(uint32_t frames, float* out);

  uint64_t time() const { return t_; }  ///< samples rendered
  /// The sample the scene ends at: its duration, else the last event plus the tail.
  uint64_t end() const { return end_; }
  /// Every event played and every mode rung out (to the retire threshold).
  bool rung_out() const;
  ScenePlayer& player() { return player_; }
  const Synth& synth() const { return player_.synth(); }

 private:
  uint32_t apply_moves(uint32_t frames);
  uint32_t apply_impacts(uint32_t frames);
  void push_contacts(uint32_t frames);

  const Scene& scene_;
  double fs_;
  SceneShakers shakers_;
  std::vector<SceneContact> contacts_;
  std::vector<std::size_t> contact_next_;  // per contact: its next point to queue
  ScenePlayer player_;
  const std::vector<ObjectModes>& objects_;
  uint32_t max_frames_;
  std::size_t next_ = 0, next_move_ = 0, next_shake_ = 0;
  double last_event_ = 0;
  uint64_t t_ = 0, end_ = 0;
};

}  // namespace chladni::runtime
