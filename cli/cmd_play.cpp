// chladni play SCENE.json: a scene through an audio device (RtAudio: JACK, ALSA or PulseAudio),
// its timeline pulled from the device's callback; latency and underruns reported at the end.
#include <RtAudio.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <thread>

#include "chladni/core/error.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/runtime/scene/scene_timeline.hpp"
#include "commands.hpp"
#include "play_churn.hpp"
#include "scene_args.hpp"

namespace chladni::cli {
namespace {

struct PlayArgs : SceneArgs {
  std::string scene, api = "auto";
  int device = -1;
  uint32_t buffer = 256;
  double duration = 0, churn = 0;
  uint32_t churn_alive = 64;
  bool list = false;
};

// Shared between the callback (audio thread) and the main thread.
struct Playback {
  runtime::SceneTimeline* timeline = nullptr;
  PlayChurn* churn = nullptr;
  int channels = 2;
  uint64_t stop_at = 0;
  double budget_ms = 0;  // one buffer's duration
  std::atomic<uint64_t> underruns{0}, callbacks{0}, first_underrun{0}, late{0};
  std::atomic<double> worst_ms{0};
  std::atomic<bool> done{false}, failed{false};
};

int callback(void* out, void*, unsigned int frames, double, RtAudioStreamStatus status,
             void* user) {
  auto& p = *static_cast<Playback*>(user);
  const auto t0 = std::chrono::steady_clock::now();
  if ((status & RTAUDIO_OUTPUT_UNDERFLOW) && p.underruns.fetch_add(1) == 0)
    p.first_underrun = p.callbacks.load() + 1;
  auto* buf = static_cast<float*>(out);
  const uint64_t now = p.timeline->time();
  const uint32_t n = static_cast<uint32_t>(std::min<uint64_t>(frames, p.stop_at - now));
  try {
    p.timeline->render(n, buf);
    if (p.churn && !p.churn->mix(buf, n)) p.failed = true;
  } catch (...) {  // nothing may leave the audio thread; the main thread reports it
    p.failed = true;
  }
  std::memset(buf + std::size_t(n) * p.channels, 0,
              sizeof(float) * (frames - n) * std::size_t(p.channels));
  p.callbacks.fetch_add(1);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (ms > p.worst_ms.load()) p.worst_ms = ms;
  if (ms > p.budget_ms) p.late.fetch_add(1);
  if (p.timeline->time() >= p.stop_at || p.failed) {
    p.done = true;
    return 1;  // stop once this buffer has played
  }
  return 0;
}

RtAudio::Api parse_api(const std::string& name) {
  if (name == "auto") return RtAudio::UNSPECIFIED;
  if (name == "jack") return RtAudio::UNIX_JACK;
  if (name == "alsa") return RtAudio::LINUX_ALSA;
  if (name == "pulse") return RtAudio::LINUX_PULSE;
  throw InputError("--api: unknown audio API '" + name + "' (auto, jack, alsa, pulse)");
}

void list_devices(RtAudio& audio) {
  std::printf("audio API %s\n", RtAudio::getApiDisplayName(audio.getCurrentApi()).c_str());
  for (unsigned d = 0; d < audio.getDeviceCount(); ++d) {
    const RtAudio::DeviceInfo info = audio.getDeviceInfo(d);
    if (info.probed && info.outputChannels > 0)
      std::printf("  %u: %s (%u output channels%s)\n", d, info.name.c_str(), info.outputChannels,
                  info.isDefaultOutput ? ", default" : "");
  }
}

void play(const PlayArgs& a, const Scene& scene) {
  // Made before the stream and gone after it: the callback renders through it.
  std::unique_ptr<PlayChurn> churn;
  if (a.churn > 0)
    churn = std::make_unique<PlayChurn>(a.churn, a.churn_alive, scene.sample_rate, scene.channels,
                                        a.buffer);
  RtAudio audio(parse_api(a.api));
  if (audio.getDeviceCount() == 0)
    throw InputError("no audio device on " + RtAudio::getApiDisplayName(audio.getCurrentApi()) +
                     " (is a sound server running? --api jack|alsa|pulse)");
  PlayArgs live = a;
  live.live = true;
  runtime::PreparedScene prepared = prepare(scene, live);
  runtime::SceneTimeline timeline(scene, prepared);
  Playback p;
  p.timeline = &timeline;
  p.churn = churn.get();
  p.channels = scene.channels;
  // A pipelined GPU hands the last samples back the filterbank's latency later.
  p.stop_at =
      (a.duration > 0 ? runtime::first_sample(a.duration, scene.sample_rate) : timeline.end()) +
      prepared.filterbank->latency();
  RtAudio::StreamParameters out;
  out.deviceId = a.device >= 0 ? static_cast<unsigned>(a.device) : audio.getDefaultOutputDevice();
  out.nChannels = static_cast<unsigned>(scene.channels);
  unsigned frames = a.buffer;
  RtAudio::StreamOptions options;
  options.streamName = "chladni";
  audio.openStream(&out, nullptr, RTAUDIO_FLOAT32, static_cast<unsigned>(scene.sample_rate),
                   &frames, &callback, &p, &options);
  const long latency = audio.getStreamLatency();
  p.budget_ms = 1e3 * frames / scene.sample_rate;
  if (churn) churn->start();
  audio.startStream();
  const auto t0 = std::chrono::steady_clock::now();
  while (!p.done && audio.isStreamRunning())
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  while (audio.isStreamRunning()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (audio.isStreamOpen()) audio.closeStream();
  if (churn) churn->stop();
  if (p.failed) throw InternalError("play: the synthesis failed in the audio callback");
  if (!a.quiet) {
    const uint32_t fb_latency = prepared.filterbank->latency();
    std::printf(
        "%s, device %u (%s): %u frames per buffer, %d Hz, stream latency %ld frames "
        "(%.1f ms), filterbank latency %u frames (%.1f ms)\n",
        RtAudio::getApiDisplayName(audio.getCurrentApi()).c_str(), out.deviceId,
        audio.getDeviceInfo(out.deviceId).name.c_str(), frames, scene.sample_rate, latency,
        1e3 * double(latency) / scene.sample_rate, fb_latency,
        1e3 * double(fb_latency) / scene.sample_rate);
    std::printf("played %.3f s in %.3f s: %llu callbacks, worst %.3f ms of %.3f ms\n",
                double(timeline.time()) / scene.sample_rate, wall,
                static_cast<unsigned long long>(p.callbacks.load()), p.worst_ms.load(),
                1e3 * frames / scene.sample_rate);
  }
  // Late callbacks are ours (the synthesis took longer than the buffer lasts); underruns are
  // what the server reported, which on a machine without real-time scheduling includes its own
  // late wake-ups.
  if (churn)
    std::printf(
        "churn: %llu steel bars spawned and struck, the oldest of %u removed for each "
        "(%llu spawns refused)\n",
        static_cast<unsigned long long>(churn->spawned()), a.churn_alive,
        static_cast<unsigned long long>(churn->refused()));
  std::printf("late callbacks %llu, underruns %llu", static_cast<unsigned long long>(p.late.load()),
              static_cast<unsigned long long>(p.underruns.load()));
  if (p.underruns)
    std::printf(" (the first in callback %llu)",
                static_cast<unsigned long long>(p.first_underrun.load()));
  std::printf("\n");
}

void run_play(const PlayArgs& a) {
  if (a.list) {
    RtAudio audio(parse_api(a.api));
    return list_devices(audio);
  }
  if (a.scene.empty()) throw InputError("name a scene file (chladni play SCENE.json)");
  Scene scene = load_scene(a.scene);
  try {
    play(a, scene);
  } catch (const RtAudioError& e) {
    throw InputError(std::string("audio device: ") + e.what());
  } catch (const InputError& e) {
    throw naming_file(a.scene, e);
  }
}

}  // namespace

void add_play(CLI::App& app) {
  auto a = std::make_shared<PlayArgs>();
  CLI::App* cmd = app.add_subcommand("play", "Play a scene (JSON) through an audio device");
  cmd->add_option("scene", a->scene, "Scene file (docs/scene-format.md)");
  cmd->add_option("--api", a->api, "Audio API: auto, jack, alsa, pulse")->capture_default_str();
  cmd->add_option("--device", a->device, "Output device (--list-devices; default: the API's)")
      ->check(CLI::Range(0, 4096));
  cmd->add_option("--buffer", a->buffer, "Frames per device buffer")
      ->check(CLI::Range(16, 16384))
      ->capture_default_str();
  cmd->add_option("--duration", a->duration, "Seconds to play (0: the scene's own end)")
      ->check(finite_in(0, 3600));
  cmd->add_flag("--list-devices", a->list, "List the API's output devices and stop");
  cmd->add_option("--churn", a->churn,
                  "A spawn storm beside the scene: spawn and strike a steel bar this many times a "
                  "second through the C API, removing the oldest (0: none)")
      ->check(finite_in(0, 20000));
  cmd->add_option("--churn-alive", a->churn_alive, "Bars alive at once in the storm")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  add_scene_options(*cmd, *a);
  cmd->callback([a] { run_play(*a); });
}

}  // namespace chladni::cli
