// chladni shake INSTRUMENT -o OUT.wav: PhISEM particle sounds (maraca, rain, gravel in a bowl...)
// on the CPU or GPU filterbank, with the instrument's resonances or a soundbank's modes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "commands.hpp"
#include "parse_choices.hpp"
#include "spectrogram.hpp"

namespace chladni::cli {
namespace {

struct ShakeArgs {
  std::string instrument, output, bank, backend = "cpu", format = "float", listener = "0,0,1";
  SpectrogramArgs spectrogram;
  double duration = 2.0, rate = 4.0, particles = 0, energy = 0.5, impulse = 1e-3;
  double normalize_db = NAN;
  int sample_rate = 48000, threads = 0;
  uint32_t voices = 1, block = 256, contacts = 8;
  uint64_t seed = 1;
  bool list = false, quiet = false;
};

void list_instruments() {
  std::printf("%-12s %-9s %-5s %s\n", "instrument", "particles", "res", "what (source)");
  for (const runtime::PhisemPreset& p : runtime::phisem_presets())
    std::printf("%-12s %-9g %-5zu %s (%s)\n", p.name.c_str(), p.objects, p.resonances.size(),
                p.title.c_str(), p.source.c_str());
}

// The voices: the instrument's resonances, or the soundbank's modes at the listener.
std::vector<runtime::ShakerVoice> make_voices(const ShakeArgs& a,
                                              const runtime::PhisemPreset& preset, double fs,
                                              int channels) {
  std::unique_ptr<ModalModel> model;
  runtime::ObjectModes object;
  if (!a.bank.empty()) {
    model = std::make_unique<ModalModel>(
        runtime::playable_model(read_soundbank(a.bank), "object", fs, a.bank));
    // Each voice keeps, per contact point, a gain for every mode: bound that before making it.
    const double gains = double(a.voices) * a.contacts * double(model->mode_count());
    if (gains > 6.4e7)
      throw InputError("--voices " + std::to_string(a.voices) + " x --contacts " +
                       std::to_string(a.contacts) + " x " + std::to_string(model->mode_count()) +
                       " modes of " + a.bank +
                       " is more than the 64 million contact gains a shake may hold");
    object = runtime::object_modes(*model);
    runtime::gains_at_listener(*model, object, parse_vec3(a.listener, "--listener"));
  }
  std::vector<runtime::ShakerVoice> voices;
  for (uint32_t v = 0; v < a.voices; ++v) {
    runtime::ShakerVoice sv = a.bank.empty()
                                  ? runtime::instrument_voice(preset, fs, a.particles)
                                  : runtime::object_voice(preset, object, fs, a.impulse, a.contacts,
                                                          a.seed + v, a.particles);
    if (channels == 2) {  // constant-power spread of the voices from left to right
      const double theta = (double(v) + 0.5) / a.voices * std::numbers::pi / 2;
      sv.pan[0] = static_cast<float>(std::cos(theta));
      sv.pan[1] = static_cast<float>(std::sin(theta));
    }
    voices.push_back(std::move(sv));
  }
  return voices;
}

std::unique_ptr<runtime::Filterbank> make_shake_filterbank(
    const ShakeArgs& a, int channels, const std::vector<runtime::ShakerVoice>& voices) {
  std::size_t slots = 0;
  for (const auto& v : voices) slots += v.resonances.size();
  runtime::FilterbankRequest req;
  req.channels = channels;
  req.threads = a.threads;
  req.capacity = static_cast<uint32_t>(std::max<std::size_t>(slots, 64));
  req.max_frames = std::max<uint32_t>(a.block, 256);
  req.max_streams = a.voices;
  return make_filterbank(a.backend, req);
}

// The peak before --normalize; a non-finite sample is a bug, not a loud sound.
double peak_and_normalize(AudioBuffer& audio, double normalize_db) {
  double peak = 0;
  for (float x : audio.samples) {
    if (!std::isfinite(x)) throw InternalError("shake: the synthesis produced a non-finite sample");
    peak = std::max(peak, double(std::abs(x)));
  }
  if (!std::isnan(normalize_db) && peak > 0) {
    const double g = std::pow(10.0, normalize_db / 20.0) / peak;
    for (float& x : audio.samples) x = static_cast<float>(x * g);
  }
  return peak;
}

void shake_spectrogram(const ShakeArgs& a, const AudioBuffer& audio,
                       const std::vector<runtime::TimedShake>& shakes) {
  plot::Events marks{{}, "shakes"};
  for (const auto& s : shakes)
    if (marks.times.empty() || s.time > marks.times.back()) marks.times.push_back(s.time);
  char title[256];
  std::snprintf(title, sizeof title, "shake %s: %u voice%s, %.3g shakes/s, energy %.3g%s%s",
                a.instrument.c_str(), a.voices, a.voices == 1 ? "" : "s", a.rate, a.energy,
                a.bank.empty() ? "" : ", on ", a.bank.c_str());
  write_spectrogram(a.spectrogram, audio, title, marks, a.quiet);
}

void run_shake(const ShakeArgs& a) {
  if (a.list) return list_instruments();
  if (a.instrument.empty()) throw InputError("name an instrument (chladni shake --list)");
  if (a.output.empty()) throw InputError("-o OUT.wav is required");
  check_output_path(a.output, "output");
  if (!a.spectrogram.path.empty()) check_output_path(a.spectrogram.path, "--spectrogram");
  const runtime::PhisemPreset& preset = runtime::phisem_preset(a.instrument);
  const SampleFormat format = parse_sample_format(a.format);
  const double fs = a.sample_rate;
  const int channels = a.voices > 1 ? 2 : 1;
  const std::vector<runtime::ShakerVoice> voices = make_voices(a, preset, fs, channels);

  auto fb = make_shake_filterbank(a, channels, voices);
  const bool gpu = fb->name().rfind("gpu", 0) == 0;  // make_filterbank may have fallen back
  runtime::ShakerBankOptions bo;
  bo.sample_rate = fs;
  bo.max_voices = a.voices;
  bo.seed = a.seed;
  bo.threads = a.threads;
  bo.excitation = gpu ? runtime::ExcitationBackend::Gpu : runtime::ExcitationBackend::Cpu;
  runtime::ShakerBank bank(*fb, bo);
  for (const auto& v : voices) bank.add_voice(v);

  // Shake over all but the last quarter second (at most a quarter of the sound): a tail rings.
  const double until = std::max(a.duration - std::min(0.25, a.duration / 4), 1e-9);
  const auto shakes =
      runtime::regular_shakes(a.voices, a.rate, until, static_cast<float>(a.energy));
  const auto t0 = std::chrono::steady_clock::now();
  AudioBuffer audio = runtime::render_shaker(bank, channels, fs, shakes, a.duration, a.block);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double peak = peak_and_normalize(audio, a.normalize_db);
  write_wav(a.output, audio, format);
  if (!a.quiet) {
    uint64_t collisions = 0;
    for (uint32_t v = 0; v < bank.voice_count(); ++v) collisions += bank.state(int(v)).collisions;
    std::printf("%s: %u voice%s x %zu resonances%s, %zu shakes, %llu collisions\n",
                preset.title.c_str(), a.voices, a.voices == 1 ? "" : "s",
                voices[0].resonances.size(), a.bank.empty() ? "" : (" (" + a.bank + ")").c_str(),
                shakes.size(), static_cast<unsigned long long>(collisions));
    std::printf("backend %s, excitation on the %s; %.3f s in %.3f s (%.1fx real time); peak %.4g\n",
                fb->name().c_str(), bank.backend_name().c_str(), a.duration, wall,
                wall > 0 ? a.duration / wall : 0.0, peak);
    std::printf("wrote %s\n", a.output.c_str());
  }
  if (!a.spectrogram.path.empty()) shake_spectrogram(a, audio, shakes);
  if (std::isnan(a.normalize_db) && peak > 1.0 && format != SampleFormat::Float32)
    std::fprintf(stderr, "warning: peak %.3g exceeds full scale and was clipped; use --normalize\n",
                 peak);
}

}  // namespace

void add_shake(CLI::App& app) {
  auto a = std::make_shared<ShakeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "shake", "Particle sounds (PhISEM): shakers, rain, gravel on a soundbank's object");
  cmd->add_option("instrument", a->instrument, "Instrument (--list shows them)");
  cmd->add_option("-o,--output", a->output, "Output WAV file");
  cmd->add_flag("--list", a->list, "List the instruments and their sources");
  cmd->add_option("--duration", a->duration, "Seconds of sound")
      ->check(finite_above(0, 3600))
      ->capture_default_str();
  cmd->add_option("--shakes-per-second", a->rate, "Shakes per second and voice")
      ->check(finite_above(0, 1000))
      ->capture_default_str();
  cmd->add_option("--energy", a->energy, "Energy each shake adds (0-1]")
      ->check(finite_above(0, 1))
      ->capture_default_str();
  cmd->add_option("--particles", a->particles, "Particle count (0: the instrument's)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--voices", a->voices, "Simultaneous voices (stereo when > 1)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  cmd->add_option("--bank", a->bank,
                  "Soundbank whose modes resonate (particles strike random surface points)");
  cmd->add_option("--contacts", a->contacts, "Surface points a bank voice's shakes move between")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  cmd->add_option("--impulse", a->impulse, "N*s per unit of excitation on a bank's object")
      ->check(finite_above(0, 1e3))
      ->capture_default_str();
  cmd->add_option("--listener", a->listener, "Listener X,Y,Z (m, object frame) for --bank")
      ->capture_default_str();
  cmd->add_option("--seed", a->seed, "Random seed (same seed, same sound on either backend)")
      ->capture_default_str();
  cmd->add_option("--backend", a->backend, "Filterbank and excitation: cpu or gpu")
      ->capture_default_str();
  cmd->add_option("--threads", a->threads, "CPU threads (0: all)")
      ->check(thread_count())
      ->capture_default_str();
  cmd->add_option("--sample-rate", a->sample_rate, "Hz")
      ->check(CLI::Range(8000, 384000))
      ->capture_default_str();
  cmd->add_option("--block", a->block, "Frames per filterbank call")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  cmd->add_option("--normalize", a->normalize_db, "Scale so the peak is at this level (dBFS)")
      ->check(finite_in(-120, 0));
  cmd->add_option("--format", a->format, "Sample format: float, pcm24, pcm16")
      ->capture_default_str();
  add_spectrogram_options(*cmd, a->spectrogram);
  cmd->add_flag("-q,--quiet", a->quiet, "Print nothing but errors");
  cmd->callback([a] { run_shake(*a); });
}

}  // namespace chladni::cli
