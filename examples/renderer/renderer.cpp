// A game's renderer with Chladni inside: Bullet drops sounding bodies onto a floor, a Vulkan
// window (SDL2) draws them, and their contacts sound through the C API's runtime running on the
// window's own Vulkan device and queue, out through SDL2's audio device.
//
// The threads are a game's: the main thread steps the physics to the audio clock, posts impacts
// and poses (game and control roles) and draws; SDL's audio thread calls chladni_runtime_render.
// The runtime records its compute work on the renderer's queue under the renderer's queue lock.
//
// Checks what it can of itself, for a headless run (Xvfb, SDL's dummy audio driver): a frame read
// back from the swapchain must show the bodies; every impact in the log must sound in the
// captured output within one audio block of being posted, and each body's first landing must
// start a sound there. Exit 0 when all hold.
//
// Usage: renderer [--seconds S] [--cpu] [--frame OUT.ppm] [--wav OUT.wav] [--log IMPACTS.csv]
#include <SDL.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "chladni/chladni.h"
#include "physics.hpp"
#include "vulkan_window.hpp"

namespace {

constexpr int kRate = 48000;
constexpr uint16_t kBlock = 256;

void check(chladni_status s, const char* what) {
  if (s != CHLADNI_OK) throw std::runtime_error(std::string(what) + ": " + chladni_last_error());
}

struct Options {
  double seconds = 3.5;
  bool cpu = false;
  std::string frame, wav, log = "renderer_impacts.csv";
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool value = i + 1 < argc;
    if (a == "--seconds" && value)
      o.seconds = std::stod(argv[++i]);
    else if (a == "--cpu")
      o.cpu = true;
    else if (a == "--frame" && value)
      o.frame = argv[++i];
    else if (a == "--wav" && value)
      o.wav = argv[++i];
    else if (a == "--log" && value)
      o.log = argv[++i];
    else
      throw std::runtime_error("unknown argument " + a);
  }
  if (!(o.seconds > 0 && o.seconds <= 600)) throw std::runtime_error("--seconds: (0, 600]");
  return o;
}

// The audio thread's side: renders into SDL's buffer and keeps a copy (preallocated) for the
// checks.
struct Audio {
  chladni_runtime* rt = nullptr;
  std::vector<float> captured;
  std::atomic<std::size_t> frames{0};
  std::atomic<bool> failed{false};
};

void audio_callback(void* user, Uint8* stream, int bytes) {
  auto& a = *static_cast<Audio*>(user);
  auto* out = reinterpret_cast<float*>(stream);
  const uint32_t n = uint32_t(bytes / (2 * sizeof(float)));
  if (chladni_runtime_render(a.rt, out, n) != CHLADNI_OK) {
    a.failed = true;
    std::fill(out, out + 2 * n, 0.0f);
  }
  const std::size_t at = a.frames.load(std::memory_order_relaxed);
  const std::size_t keep = std::min<std::size_t>(n, a.captured.size() / 2 - at);
  std::copy(out, out + 2 * keep, a.captured.begin() + std::ptrdiff_t(2 * at));
  a.frames.store(at + keep, std::memory_order_release);
}

void write_ppm(const std::string& path, const VulkanWindow& w) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path);
  std::fprintf(f, "P6\n%d %d\n255\n", w.width(), w.height());
  std::fwrite(w.captured.data(), 1, w.captured.size(), f);
  std::fclose(f);
}

void write_wav(const std::string& path, const float* x, std::size_t frames) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path);
  const uint32_t data = uint32_t(frames * 8), riff = 36 + data, fmt_size = 16, rate = kRate,
                 bytes_per_s = kRate * 8;
  const uint16_t fmt = 3, ch = 2, align = 8, bits = 32;
  std::fwrite("RIFF", 1, 4, f), std::fwrite(&riff, 4, 1, f), std::fwrite("WAVEfmt ", 1, 8, f);
  std::fwrite(&fmt_size, 4, 1, f), std::fwrite(&fmt, 2, 1, f), std::fwrite(&ch, 2, 1, f);
  std::fwrite(&rate, 4, 1, f), std::fwrite(&bytes_per_s, 4, 1, f), std::fwrite(&align, 2, 1, f);
  std::fwrite(&bits, 2, 1, f), std::fwrite("data", 1, 4, f), std::fwrite(&data, 4, 1, f);
  std::fwrite(x, sizeof(float), frames * 2, f);
  std::fclose(f);
}

// Pixels unlike the background: the bodies and the floor.
std::size_t drawn_pixels(const VulkanWindow& w, const float background[4]) {
  std::size_t n = 0;
  for (std::size_t i = 0; i + 2 < w.captured.size(); i += 3) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d += std::abs(int(w.captured[i + c]) - int(background[c] * 255));
    n += d > 24;
  }
  return n;
}

float peak(const float* x, std::size_t frames, std::size_t a, std::size_t b) {
  float p = 0;
  for (std::size_t i = 2 * a; i < 2 * std::min(b, frames); ++i) p = std::max(p, std::abs(x[i]));
  return p;
}

// Every impact must sound within `window` frames of its sample (the block being rendered when it
// was posted and the next, and the backend's latency); one with no other in the 0.25 s before (a
// body's first landing: they are let go 0.6 s apart) must also start a sound there: the output's
// peak rises over the block before by half. A bounce of a body still ringing from its landing need
// not.
struct Heard {
  std::size_t sounding = 0, isolated = 0, onsets = 0;
};

Heard check_impacts(const std::vector<Physics::Impact>& impacts, const float* x, std::size_t frames,
                    std::size_t window) {
  Heard h;
  const float all = peak(x, frames, 0, frames);
  double last = -1;
  for (const Physics::Impact& im : impacts) {
    const std::size_t s = std::size_t(std::lround(im.time * kRate));
    const float after = peak(x, frames, s, s + window);
    h.sounding += after > 1e-4f * all;
    if (last < 0 || im.time - last >= 0.25) {
      ++h.isolated;
      const float before = peak(x, frames, s > kBlock ? s - kBlock : 0, s);
      h.onsets += after > 1.5f * before;
    }
    last = im.time;
  }
  return h;
}

// The runtime on the window's device and queue (or the CPU), its submits under the window's
// queue lock. The device description is copied at creation.
chladni_runtime* make_runtime(VulkanWindow& window, bool cpu) {
  chladni_vulkan_device shared{};
  shared.instance = window.instance;
  shared.physical_device = window.physical;
  shared.device = window.device;
  shared.queue_family = window.family;
  shared.queue_index = 0;
  shared.lock_queue = [](void* u) { static_cast<VulkanWindow*>(u)->queue_lock.lock(); };
  shared.unlock_queue = [](void* u) { static_cast<VulkanWindow*>(u)->queue_lock.unlock(); };
  shared.user = &window;
  chladni_config config;
  chladni_config_default(&config);
  config.sample_rate = kRate;
  config.block_size = kBlock;
  config.backend = cpu ? CHLADNI_BACKEND_CPU : CHLADNI_BACKEND_GPU;
  config.vulkan = cpu ? nullptr : &shared;
  config.threads = 1;
  chladni_runtime* rt = nullptr;
  check(chladni_runtime_create(&config, &rt), "chladni_runtime_create");
  return rt;
}

// SDL's audio device, paused, its thread calling audio_callback; `got` is what it granted.
SDL_AudioDeviceID open_audio(Audio& audio, SDL_AudioSpec& got) {
  SDL_AudioSpec want{};
  want.freq = kRate;
  want.format = AUDIO_F32SYS;
  want.channels = 2;
  want.samples = kBlock;
  want.callback = audio_callback;
  want.userdata = &audio;
  const SDL_AudioDeviceID dev = SDL_OpenAudioDevice(nullptr, 0, &want, &got, 0);
  if (!dev) throw std::runtime_error(std::string("SDL_OpenAudioDevice: ") + SDL_GetError());
  std::printf("audio: %s, %u frames a buffer\n", SDL_GetCurrentAudioDriver(),
              unsigned(got.samples));
  return dev;
}

}  // namespace

int main(int argc, char** argv) try {
  const Options opt = parse(argc, argv);
  if (SDL_Init(SDL_INIT_VIDEO | SDL_INIT_AUDIO) != 0)
    throw std::runtime_error(std::string("SDL_Init: ") + SDL_GetError());
  VulkanWindow window("Chladni: falling objects", 640, 480);
  std::printf("Vulkan device: %s (queue family %u, shared with the audio runtime)\n",
              window.device_name.c_str(), window.family);

  Audio audio;
  audio.rt = make_runtime(window, opt.cpu);
  std::printf("runtime: %s\n", chladni_runtime_backend(audio.rt));
  const double ear[3] = {0, -1.2, 0.3}, fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1};
  check(chladni_listener_set(audio.rt, 0, ear, fwd, up), "chladni_listener_set");
  Physics physics(audio.rt);
  audio.captured.assign(std::size_t((opt.seconds + 2) * kRate) * 2, 0.0f);
  SDL_AudioSpec got{};
  const SDL_AudioDeviceID dev = open_audio(audio, got);

  FILE* log = std::fopen(opt.log.c_str(), "w");
  if (!log) throw std::runtime_error("cannot write " + opt.log);
  std::fprintf(log, "time_s,body,impulse_ns\n");
  const float background[4] = {0.08f, 0.09f, 0.12f, 1};
  SDL_PauseAudioDevice(dev, 0);
  const Uint64 t0 = SDL_GetTicks64();
  std::size_t frames_drawn = 0, drawn = 0;
  bool captured = false;
  for (;;) {
    SDL_Event e;
    bool quit = false;
    while (SDL_PollEvent(&e)) quit |= e.type == SDL_QUIT;
    const double now = double(SDL_GetTicks64() - t0) / 1000;
    if (quit || now >= opt.seconds) break;
    // The audio clock is the simulation's: a sound lands on the step that made it, however late
    // the audio thread runs behind the wall clock (a busy machine).
    physics.advance_to(chladni_runtime_time(audio.rt), log);
    const bool capture = !captured && now >= 1.0;
    window.draw(background, physics.rects(window.width(), window.height()), capture);
    if (capture) {
      captured = true;
      drawn = drawn_pixels(window, background);
      if (!opt.frame.empty()) write_ppm(opt.frame, window);
    }
    ++frames_drawn;
    // 60 frames a second, as a display would pace them (a virtual one does not).
    const Uint64 next = t0 + frames_drawn * 1000 / 60, ticks = SDL_GetTicks64();
    if (next > ticks) SDL_Delay(Uint32(next - ticks));
  }
  SDL_PauseAudioDevice(dev, 1);
  SDL_CloseAudioDevice(dev);
  std::fclose(log);

  const std::size_t frames = audio.frames.load(std::memory_order_acquire);
  const std::size_t latency = std::size_t(std::lround(chladni_runtime_latency(audio.rt) * kRate));
  // Posted at clock t while the audio thread may already be rendering the block from t: it lands
  // there or at the next block's start, and is heard the backend's latency later.
  const std::size_t window_frames = 2 * std::size_t(got.samples) + latency;
  const Heard heard =
      check_impacts(physics.impacts(), audio.captured.data(), frames, window_frames);
  if (!opt.wav.empty()) write_wav(opt.wav, audio.captured.data(), frames);
  std::printf("%zu frames drawn in %.1f s; the frame at 1 s has %zu drawn pixels of %d\n",
              frames_drawn, opt.seconds, drawn, window.width() * window.height());
  std::printf(
      "%zu impacts, %zu sounding within the audio block they were posted in, the next and the "
      "latency (%zu frames); %zu after 0.25 s without one, %zu of them starting a sound there; "
      "%.2f s of audio\n",
      physics.impacts().size(), heard.sounding, window_frames, heard.isolated, heard.onsets,
      double(frames) / kRate);
  const bool ok = !audio.failed && captured && drawn > std::size_t(window.width()) * 4 &&
                  !physics.impacts().empty() && heard.sounding == physics.impacts().size() &&
                  heard.isolated >= 3 && heard.onsets == heard.isolated;
  physics.clear();
  chladni_runtime_destroy(audio.rt);
  SDL_Quit();
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "error: %s\n", e.what());
  return 2;
}
