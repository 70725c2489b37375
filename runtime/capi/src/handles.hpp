#pragma once
// The C API's handles and helpers (internal).
#include <atomic>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "chladni/chladni.h"
#include "chladni/core/error.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/scene/scene_player.hpp"
#include "spsc_queue.hpp"

namespace chladni::capi {

enum class Kind : uint8_t { Impact, Move, Listener, Shake };

// One posted command, plain data (copied through the queue).
struct Command {
  Kind kind;
  uint32_t object;  // a shaker's index for Shake
  double time;
  double impulse, contact;  // impulse: a shake's energy
  int64_t vertex;
  double a[3], b[3], c[3], q[4];  // direction/point/-, position/forward/up, orientation
};

/// Records `message` as this thread's last error; returns `status`.
chladni_status fail(chladni_status status, std::string message);

// Runs `f`, turning every exception into a status and a message naming the call.
template <class F>
chladni_status guarded(const char* call, F&& f) {
  try {
    return f();
  } catch (const InputError& e) {
    return fail(CHLADNI_INPUT_ERROR, std::string(call) + ": " + e.what());
  } catch (const gpu::NoDeviceError& e) {
    return fail(CHLADNI_NO_DEVICE, std::string(call) + ": " + e.what());
  } catch (const std::exception& e) {
    return fail(CHLADNI_INTERNAL_ERROR, std::string(call) + ": " + e.what());
  } catch (...) {
    return fail(CHLADNI_INTERNAL_ERROR, std::string(call) + ": unknown error");
  }
}

/// InputError unless `v` holds 3 finite numbers (and, with `nonzero`, is not zero).
void need_vector(const double* v, const char* what, bool nonzero = true);
/// The unit quaternion of `q` (w, x, y, z); InputError when not finite or zero.
Quat unit_quaternion(const double* q);

}  // namespace chladni::capi

struct chladni_bank {
  std::unique_ptr<chladni::ModalModel> model;  // soundbanks
  std::vector<chladni::InlineMode> inline_modes;
  chladni::runtime::ObjectModes modes;
  double mass = 0;  // kg: the surface's volume times the density (0 for inline modes)
};

struct chladni_runtime {
  explicit chladni_runtime(const chladni_config& c);
  void drain();
  void apply_due(uint64_t t, uint32_t frames);
  uint32_t until_next_pose(uint32_t frames) const;
  uint64_t sample_of(const chladni::capi::Command& c) const;

  chladni_config config;
  std::unique_ptr<chladni::runtime::Filterbank> fb;
  std::string name;
  std::unique_ptr<chladni::runtime::ScenePlayer> player;
  std::vector<std::unique_ptr<chladni_bank>> banks;
  chladni::runtime::SpscQueue<chladni::capi::Command> queue;
  std::vector<chladni::capi::Command> pending;  // drained commands, by time; capacity fixed
  uint64_t now = 0;                             // samples rendered (audio thread)
  std::atomic<uint64_t> clock{0};  // `now`, published for chladni_time on other threads
};
