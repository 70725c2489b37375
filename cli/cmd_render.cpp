// chladni render SCENE.json -o OUT.wav: plays a scene's impacts through the modal filterbank.
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "backend.hpp"
#include "chladni/core/audio_file.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/render.hpp"
#include "chladni/runtime/scene_objects.hpp"
#include "commands.hpp"

namespace chladni::cli {
namespace {

struct RenderArgs {
  std::string scene, output, backend = "cpu", isa = "auto", format = "float";
  int sample_rate = 0, threads = 0;
  uint32_t block = 256, max_modes = 0, gain_ramp = 256;
  double normalize_db = NAN, retire_db = -100;
  bool quiet = false;
};

void render_loaded(const RenderArgs& a, Scene& scene, SampleFormat format) {
  if (!a.quiet)
    std::printf("scene %s: %zu objects, %zu impacts, %zu moves, %zu shakes\n", a.scene.c_str(),
                scene.objects.size(), scene.events.size(), scene.moves.size(), scene.shakes.size());
  const std::vector<runtime::PlayableObject> playable = runtime::resolve_objects(scene);
  std::vector<runtime::ObjectModes> objects;
  for (std::size_t k = 0; k < playable.size(); ++k) {
    objects.push_back(playable[k].modes);
    if (!a.quiet)
      std::printf("  %-12s %s\n", scene.objects[k].name.c_str(), playable[k].summary.c_str());
  }

  std::size_t total_modes = 0;
  for (const auto& o : objects) total_modes += o.modes.size();
  BackendRequest req;
  req.backend = a.backend;
  req.channels = scene.channels;
  req.threads = a.threads;
  req.isa = a.isa;
  const uint32_t budget =
      a.max_modes ? a.max_modes
                  : static_cast<uint32_t>(std::clamp<std::size_t>(total_modes, 1024, 1u << 20));
  // Shake events' voices sit in slots of their own above the impacts' budget.
  const runtime::SceneShakers shakers = runtime::scene_shakers(scene, objects);
  req.capacity = budget + shakers.slots;
  req.max_streams = static_cast<uint32_t>(shakers.first_event.size());
  req.max_frames = std::max<uint32_t>(a.block, 256);
  req.gain_ramp = a.gain_ramp;
  auto fb = make_filterbank(req);

  runtime::RenderOptions ro;
  ro.block = a.block;
  ro.synth.retire_db = a.retire_db;
  ro.synth.max_modes = budget;
  std::size_t transfer_modes = 0;
  for (const auto& o : objects) transfer_modes += o.transfer ? o.modes.size() : 0;
  if (a.backend == "gpu" && transfer_modes >= ro.gpu_gain_modes) {
    try {
      ro.gain_device = std::make_shared<gpu::Context>();
    } catch (const gpu::NoDeviceError&) {
      // the filterbank already warned; gains stay on the CPU
    }
  }
  runtime::RenderReport rep;
  AudioBuffer audio = runtime::render_scene(scene, objects, *fb, ro, &rep);

  double gain = 1.0;
  if (!std::isnan(a.normalize_db) && rep.peak > 0)
    gain = std::pow(10.0, a.normalize_db / 20.0) / rep.peak;
  if (gain != 1.0)
    for (float& x : audio.samples) x = static_cast<float>(x * gain);
  write_wav(a.output, audio, format);

  const double secs = double(rep.frames) / scene.sample_rate;
  if (!a.quiet) {
    std::printf("backend %s, block %u, %d Hz, %d channel%s\n", fb->name().c_str(), a.block,
                scene.sample_rate, scene.channels, scene.channels == 2 ? "s" : "");
    std::printf(
        "rendered %.3f s in %.3f s (%.1fx real time); peak %.4g%s; modes: %u resident at most, "
        "%llu retired, %llu stolen\n",
        secs, rep.seconds, rep.seconds > 0 ? secs / rep.seconds : 0.0, rep.peak,
        std::isnan(a.normalize_db) ? " Pa" : " Pa before normalization", rep.max_active_modes,
        static_cast<unsigned long long>(rep.stats.retired),
        static_cast<unsigned long long>(rep.stats.stolen));
    if (!rep.gain_backend.empty())
      std::printf("listener gains from transfer (%s): %llu updates, %.3f ms each\n",
                  rep.gain_backend.c_str(), static_cast<unsigned long long>(rep.gain_updates),
                  rep.gain_updates ? 1e3 * rep.gain_seconds / double(rep.gain_updates) : 0.0);
    std::printf("wrote %s\n", a.output.c_str());
  }
  if (std::isnan(a.normalize_db) && rep.peak > 1.0 && format != SampleFormat::Float32) {
    std::fprintf(stderr, "warning: peak %.3g exceeds full scale and was clipped; use --normalize\n",
                 rep.peak);
  }
}

void run_render(const RenderArgs& a) {
  check_output_path(a.output, "output");
  const SampleFormat format = parse_sample_format(a.format);
  Scene scene = load_scene(a.scene);
  if (a.sample_rate) scene.sample_rate = a.sample_rate;
  try {
    render_loaded(a, scene, format);
  } catch (const InputError& e) {
    throw naming_file(a.scene, e);
  }
}

}  // namespace

void add_render(CLI::App& app) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene (JSON) to a WAV file");
  cmd->add_option("scene", a->scene, "Scene file (docs/scene-format.md)")->required();
  cmd->add_option("-o,--output", a->output, "Output WAV file")->required();
  cmd->add_option("--backend", a->backend, "Filterbank: cpu or gpu (gpu falls back to cpu)")
      ->capture_default_str();
  cmd->add_option("--sample-rate", a->sample_rate, "Override the scene's sample rate (Hz)")
      ->check(CLI::Range(8000, 384000));
  cmd->add_option("--block", a->block, "Frames per filterbank call")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  cmd->add_option("--gain-ramp", a->gain_ramp,
                  "Samples over which listener and pose changes ramp the gains (at most --block; "
                  "0: at once)")
      ->check(CLI::Range(0, 65536))
      ->capture_default_str();
  cmd->add_option("--threads", a->threads, "CPU threads (0: all)")
      ->check(thread_count())
      ->capture_default_str();
  cmd->add_option("--isa", a->isa, "CPU instruction set: auto, scalar, avx2, avx512")
      ->capture_default_str();
  cmd->add_option("--max-modes", a->max_modes, "Resident mode budget (0: all modes of the scene)")
      ->check(CLI::Range(0, 1 << 24));
  cmd->add_option("--retire-db", a->retire_db, "Retire modes this far below their peak (dB)")
      ->check(finite_in(-400, 0))
      ->capture_default_str();
  cmd->add_option("--normalize", a->normalize_db, "Scale so the peak is at this level (dBFS)")
      ->check(finite_in(-120, 0));
  cmd->add_option("--format", a->format, "Sample format: float, pcm24, pcm16")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", a->quiet, "Print nothing but errors");
  cmd->callback([a] { run_render(*a); });
}

}  // namespace chladni::cli
