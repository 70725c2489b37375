#include "play_churn.hpp"

#include <algorithm>
#include <chrono>
#include <deque>
#include <random>
#include <string>

#include "chladni/core/error.hpp"

namespace chladni::cli {

PlayChurn::PlayChurn(double rate, uint32_t alive, double sample_rate, int channels,
                     uint32_t max_frames)
    : rate_(rate), alive_(alive), channels_(channels) {
  chladni_config c;
  chladni_config_default(&c);
  c.sample_rate = sample_rate;
  c.channels = channels;
  c.threads = 1;
  c.shaker_slots = 0;
  // Room for the fading ones beside the live ones: a removed bar fades over the gain ramp.
  c.max_objects = 2 * alive + 64;
  c.max_papers = 0;
  if (chladni_runtime_create(&c, &rt_) != CHLADNI_OK)
    throw InputError(std::string("--churn: ") + chladni_last_error());
  chladni_bar bar;
  chladni_bar_default(&bar);
  if (chladni_bank_from_bar(rt_, &bar, &bar_) != CHLADNI_OK)
    throw InternalError(std::string("--churn: ") + chladni_last_error());
  scratch_.resize(std::size_t(max_frames) * channels);
}

PlayChurn::~PlayChurn() {
  stop();
  chladni_runtime_destroy(rt_);
}

void PlayChurn::start() {
  control_ = std::thread([this] { run(); });
}

void PlayChurn::stop() {
  stop_ = true;
  if (control_.joinable()) control_.join();
}

// The control (and game) thread: every 1/rate s the oldest bar goes and a new one, somewhere
// around the listener, is struck 10 ms ahead of the runtime's clock.
void PlayChurn::run() {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::deque<chladni_object> live;
  const auto period = std::chrono::duration<double>(1 / rate_);
  auto next = std::chrono::steady_clock::now();
  const double identity[4] = {1, 0, 0, 0};
  while (!stop_) {
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
    if (live.size() >= alive_) {
      chladni_object_remove(rt_, live.front());
      live.pop_front();
    }
    const double at[3] = {2 * u(rng), 1 + u(rng), 0.5 * u(rng)};
    chladni_object o{0};
    if (chladni_object_spawn(rt_, bar_, at, identity, 0.2, &o) != CHLADNI_OK) {
      ++refused_;
      continue;
    }
    ++spawned_;
    live.push_back(o);
    chladni_impact hit{};
    hit.object = o;
    hit.time = chladni_runtime_time(rt_) + 0.01;
    hit.impulse = 0.002;
    hit.direction[2] = -1;
    hit.vertex = -1;
    hit.contact_time = 0.0005;
    chladni_impact_post(rt_, &hit);
  }
  for (const chladni_object& o : live) chladni_object_remove(rt_, o);
}

bool PlayChurn::mix(float* out, uint32_t frames) {
  while (frames > 0) {
    const uint32_t n =
        std::min<uint32_t>(frames, static_cast<uint32_t>(scratch_.size() / channels_));
    if (chladni_runtime_render(rt_, scratch_.data(), n) != CHLADNI_OK) return false;
    for (std::size_t i = 0; i < std::size_t(n) * channels_; ++i) out[i] += scratch_[i];
    out += std::size_t(n) * channels_;
    frames -= n;
  }
  return true;
}

}  // namespace chladni::cli
