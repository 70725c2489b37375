#pragma once
// `chladni play --churn N`: a spawn storm beside the scene, to hear and count what live scene
// changes cost a real audio device. It drives the C API as an engine would: a control thread
// spawns a struck steel bar N times a second and removes the oldest, while the device's callback
// renders the runtime's objects on top of the scene.
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "chladni/chladni.h"

namespace chladni::cli {

class PlayChurn {
 public:
  /// A runtime at the scene's rate and channel count; `alive` objects are kept, the oldest
  /// replaced `rate` times a second. Throws InputError when the runtime cannot be made.
  PlayChurn(double rate, uint32_t alive, double sample_rate, int channels, uint32_t max_frames);
  ~PlayChurn();
  PlayChurn(const PlayChurn&) = delete;
  PlayChurn& operator=(const PlayChurn&) = delete;

  void start();  ///< the control thread
  void stop();   ///< joins it
  /// Audio thread: adds `frames` frames of the runtime's objects to `out` (no allocation).
  bool mix(float* out, uint32_t frames);

  uint64_t spawned() const { return spawned_.load(); }
  uint64_t refused() const { return refused_.load(); }

 private:
  void run();

  chladni_runtime* rt_ = nullptr;
  chladni_bank bar_{0};
  double rate_;
  uint32_t alive_;
  int channels_;
  std::vector<float> scratch_;
  std::thread control_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> spawned_{0}, refused_{0};
};

}  // namespace chladni::cli
