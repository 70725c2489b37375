// chladni render SCENE.json -o OUT.wav: plays a scene's impacts through the modal filterbank.
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/runtime/scene/prepare_scene.hpp"
#include "commands.hpp"
#include "parse_choices.hpp"
#include "scene_args.hpp"
#include "spectrogram.hpp"

namespace chladni::cli {
namespace {

struct RenderArgs : SceneArgs {
  std::string scene, output, format = "float";
  int sample_rate = 0;
  double normalize_db = NAN;
  SpectrogramArgs spectrogram;
};

void render_loaded(const RenderArgs& a, Scene& scene, SampleFormat format) {
  if (!a.quiet)
    std::printf("scene %s: %zu objects, %zu impacts, %zu moves, %zu shakes\n", a.scene.c_str(),
                scene.objects.size(), scene.events.size(), scene.moves.size(), scene.shakes.size());
  runtime::PreparedScene prepared = prepare(scene, a);
  const auto& fb = prepared.filterbank;
  runtime::RenderReport rep;
  AudioBuffer audio = runtime::render_scene(scene, prepared, &rep);

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
  if (!a.spectrogram.path.empty()) {
    std::string what = "impacts";
    if (!scene.shakes.empty()) what += ", shakes";
    if (!scene.contacts.empty()) what += ", contact starts and ends";
    plot::Events marks{{}, what};
    for (const auto& e : scene.events) marks.times.push_back(e.time);
    for (const auto& e : scene.shakes) marks.times.push_back(e.time);
    for (const auto& e : scene.contacts)
      marks.times.insert(marks.times.end(), {e.time, e.end_time()});
    write_spectrogram(a.spectrogram, audio,
                      "render " + a.scene + ": " + std::to_string(scene.objects.size()) +
                          " object" + (scene.objects.size() == 1 ? "" : "s") + " on " + fb->name(),
                      marks, a.quiet);
  }
  if (std::isnan(a.normalize_db) && rep.peak > 1.0 && format != SampleFormat::Float32) {
    std::fprintf(stderr, "warning: peak %.3g exceeds full scale and was clipped; use --normalize\n",
                 rep.peak);
  }
}

void run_render(const RenderArgs& a) {
  check_output_path(a.output, "output");
  if (!a.spectrogram.path.empty()) check_output_path(a.spectrogram.path, "--spectrogram");
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
  cmd->add_option("--sample-rate", a->sample_rate, "Override the scene's sample rate (Hz)")
      ->check(CLI::Range(8000, 384000));
  add_scene_options(*cmd, *a);
  cmd->add_option("--normalize", a->normalize_db, "Scale so the peak is at this level (dBFS)")
      ->check(finite_in(-120, 0));
  cmd->add_option("--format", a->format, "Sample format: float, pcm24, pcm16")
      ->capture_default_str();
  add_spectrogram_options(*cmd, a->spectrogram);
  cmd->callback([a] { run_render(*a); });
}

}  // namespace chladni::cli
