// chladni paper-gen NAME -o DIR: the procedural example animations.
// chladni paper ANIMATION.json [--events OUT.json] [-o OUT.wav ...]: the per-frame analysis
// (events, resonators) and, with -o, the synthesized and spatialized sound.
// chladni paper-db generate|info: the sound databases.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/core/paper_animation.hpp"
#include "chladni/runtime/paper/paper_analysis.hpp"
#include "chladni/runtime/paper/paper_database.hpp"
#include "chladni/runtime/paper/paper_synth.hpp"
#include "chladni/tools/paper_db_cache.hpp"
#include "chladni/tools/paper_db_generate.hpp"
#include "chladni/tools/paper_scenarios.hpp"
#include "commands.hpp"
#include "parse_choices.hpp"
#include "progress.hpp"
#include "spectrogram.hpp"

namespace chladni::cli {
namespace {

struct GenArgs {
  std::string name, dir;
  tools::PaperScenarioOptions options;
  bool binary = false;
};

void run_gen(const GenArgs& a) {
  std::vector<std::string> names{a.name};
  if (a.name == "all") names = tools::paper_scenario_names();
  std::filesystem::create_directories(a.dir);
  for (const std::string& n : names) {
    const tools::PaperScenario s = tools::make_paper_scenario(n, a.options);
    const std::string path = (std::filesystem::path(a.dir) / (n + ".json")).string();
    write_paper_animation(path, s.animation,
                          a.binary ? PaperFrameStorage::Binary : PaperFrameStorage::Obj);
    std::printf("wrote %s: %u triangles, %u frames at %g fps (%s)\n", path.c_str(),
                unsigned(s.animation.triangles.size()), s.animation.frame_count(),
                s.animation.frame_rate, s.description.c_str());
  }
}

struct AnalyzeArgs {
  std::string animation, events, output, db, mode = "database", backend = "cpu";
  SpectrogramArgs spectrogram;
  std::vector<double> listener;
  std::uint64_t seed = 1;
  runtime::PaperAnalysisOptions options;
};

runtime::PaperSoundDb database(const std::string& dir) {
  if (!dir.empty()) return runtime::load_paper_database(dir);
  std::string note;
  runtime::PaperSoundDb db = tools::default_paper_database(tools::cache_dir(), note);
  std::printf("%s\n", note.c_str());
  return db;
}

void run_synthesis(const AnalyzeArgs& a, PaperAnimation& anim) {
  runtime::PaperSynthOptions o;
  o.mode = runtime::parse_paper_mode(a.mode);
  o.seed = a.seed;
  o.analysis = a.options;
  if (!a.listener.empty()) {
    if (a.listener.size() != 3) throw InputError("--listener: expected X,Y,Z");
    anim.listener.position = {a.listener[0], a.listener[1], a.listener[2]};
  }
  std::optional<runtime::PaperSoundDb> db;
  if (o.mode != runtime::PaperSynthMode::Modal) db = database(a.db);
  std::unique_ptr<runtime::Filterbank> fb;
  if (o.mode != runtime::PaperSynthMode::Database) {
    runtime::FilterbankRequest r;
    r.channels = 2;
    r.capacity = 1u << 18;
    r.max_frames = 1024;
    fb = make_filterbank(a.backend, r);
  }
  runtime::PaperRenderReport rep;
  const AudioBuffer audio = runtime::render_paper(anim, db ? &*db : nullptr, fb.get(), o, &rep);
  write_wav(a.output, audio);
  std::printf("wrote %s: %.2f s stereo at %d Hz, %s mode%s%s\n", a.output.c_str(),
              rep.audio_seconds, audio.sample_rate, a.mode.c_str(), fb ? " on " : "",
              fb ? fb->name().c_str() : "");
  std::printf("  %llu friction and %llu crumpling events, %llu resonators (at most %u in a frame)",
              (unsigned long long)rep.friction_events, (unsigned long long)rep.crumple_events,
              (unsigned long long)rep.resonators, rep.max_resonators_in_frame);
  if (fb) std::printf(", at most %u modal voices", rep.peak_modal_voices);
  std::printf(
      "\n  per frame: analysis %.3f ms + synthesis %.3f ms (worst frame %.3f ms); "
      "%.0fx faster than real time\n",
      rep.analysis_ms / rep.frames, rep.synthesis_ms / rep.frames, rep.worst_frame_ms,
      rep.audio_seconds / rep.wall_seconds);
  const std::string title =
      "paper " + a.animation + ": " + a.mode + " mode" + (fb ? " on " + fb->name() : std::string());
  write_spectrogram(a.spectrogram, audio, title, {rep.crumple_times, "crumpling"});
}

nlohmann::json resonator_json(const runtime::PaperResonator& r) {
  return {{"curved", r.curved},       {"constrained", r.constrained}, {"faces", r.faces},
          {"area_m2", r.area},        {"centroid", r.centroid},       {"normal", r.normal},
          {"l_r_m", r.ruling_length}, {"l_c_m", r.free_border}};
}

void run_analyze(const AnalyzeArgs& a) {
  if (!a.output.empty()) check_output_path(a.output, "output");
  if (!a.events.empty()) check_output_path(a.events, "--events");
  if (!a.spectrogram.path.empty()) check_output_path(a.spectrogram.path, "--spectrogram");
  PaperAnimation anim = load_paper_animation(a.animation);
  if (!a.output.empty()) {
    run_synthesis(a, anim);
    if (a.events.empty()) return;
  }
  runtime::PaperAnalyzer analyzer(anim, a.options);
  nlohmann::json frames = nlohmann::json::array();
  std::size_t friction = 0, crumple = 0, resonators = 0;
  double seconds = 0;
  for (std::uint32_t f = 0; f < anim.frame_count(); ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    const runtime::PaperFrameAnalysis fa = analyzer.analyze(f);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (fa.events.empty()) continue;
    nlohmann::json events = nlohmann::json::array();
    for (const runtime::PaperEvent& e : fa.events) {
      const bool fr = e.type == runtime::PaperEventType::Friction;
      (fr ? friction : crumple)++;
      resonators += e.resonators.size();
      nlohmann::json je = {{"type", fr ? "friction" : "crumple"},
                           {"amplitude", e.amplitude},
                           {"vertices", e.vertices},
                           {"centroid", e.centroid}};
      if (fr) je["obstacle"] = anim.obstacles[std::size_t(e.obstacle)].name;
      je["resonators"] = nlohmann::json::array();
      for (const auto& r : e.resonators) je["resonators"].push_back(resonator_json(r));
      events.push_back(std::move(je));
    }
    frames.push_back({{"frame", fa.frame},
                      {"time_s", fa.time},
                      {"regions", fa.regions},
                      {"events", std::move(events)}});
  }
  std::printf("%s: %u vertices, %u triangles, %u frames at %g fps (%.2f s)\n", a.animation.c_str(),
              anim.vertex_count, unsigned(anim.triangles.size()), anim.frame_count(),
              anim.frame_rate, anim.duration());
  if (analyzer.topology().flipped_faces)
    std::printf("  %u faces re-oriented to match their neighbours\n",
                analyzer.topology().flipped_faces);
  std::printf("  %zu friction and %zu crumpling events in %zu frames, %zu resonators\n", friction,
              crumple, frames.size(), resonators);
  std::printf("  analysis: %.3f ms per frame\n", 1e3 * seconds / anim.frame_count());
  if (!a.events.empty()) {
    write_file_atomic(a.events,
                      nlohmann::json{{"animation", a.animation},
                                     {"frame_rate", anim.frame_rate},
                                     {"frames", anim.frame_count()},
                                     {"ms_per_frame", 1e3 * seconds / anim.frame_count()},
                                     {"event_frames", std::move(frames)}}
                              .dump(1) +
                          "\n",
                      "--events");
    std::printf("wrote %s\n", a.events.c_str());
  }
}

struct DbArgs {
  std::string dir;
  tools::PaperDbOptions options;
  double friction_seconds = 1.0;
};

void run_db_generate(const DbArgs& a) {
  const auto t = std::chrono::steady_clock::now();
  ProgressBar progress(false);
  progress.stage("sheet modes, clips and spectra");
  const runtime::PaperSoundDb db =
      tools::generate_paper_database(a.options, [&](double f) { progress.fraction(f); });
  progress.finish();
  tools::write_paper_database(a.dir, db, a.friction_seconds, a.options.seed);
  std::size_t clips = 0, spectra = 0;
  for (const auto& e : db.entries) {
    clips += e.crumple.size();
    for (const auto& [s, v] : e.friction) spectra += v.size();
  }
  std::printf("wrote %s: %zu entries, %zu crumple clips, %zu friction recordings (%.1f s)\n",
              a.dir.c_str(), db.entries.size(), clips, spectra,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count());
}

void run_db_info(const DbArgs& a) {
  const runtime::PaperSoundDb db = runtime::load_paper_database(a.dir);
  std::size_t clips = 0, spectra = 0, samples = 0;
  for (const auto& e : db.entries) {
    clips += e.crumple.size();
    for (const auto& c : e.crumple) samples += c.size();
    for (const auto& [s, v] : e.friction) spectra += v.size();
  }
  std::string surfaces;
  for (const auto& s : db.surfaces()) surfaces += (surfaces.empty() ? "" : ", ") + s;
  std::printf(
      "%s: %s\n  %zu entries at %g Hz, %zu crumple clips (mean %.0f ms), %zu friction "
      "spectra (surfaces: %s), reference speed %g m/s\n",
      a.dir.c_str(), db.description.c_str(), db.entries.size(), db.sample_rate, clips,
      clips ? 1e3 * samples / clips / db.sample_rate : 0.0, spectra, surfaces.c_str(),
      db.friction_reference_speed);
}

}  // namespace

void add_paper(CLI::App& app) {
  auto g = std::make_shared<GenArgs>();
  auto* gen = app.add_subcommand(
      "paper-gen", "Write a procedural paper animation (slide, shake, flap, crumple or all)");
  gen->add_option("name", g->name, "Scenario: slide, shake, flap, crumple or all")->required();
  gen->add_option("-o,--output", g->dir, "Folder for NAME.json and its frames")->required();
  gen->add_option("--triangles", g->options.triangles, "Approximate triangle count (800)")
      ->check(CLI::Range(8, 2000000));
  gen->add_option("--duration", g->options.duration, "Seconds (default: the scenario's)")
      ->check(finite_above(0, 600));
  gen->add_option("--frame-rate", g->options.frame_rate, "Frames per second (60)")
      ->check(finite_in(10, 1000));
  gen->add_option("--seed", g->options.seed, "Random seed (crumple)");
  gen->add_flag("--binary", g->binary, "Store frames as one .chpaper file instead of OBJs");
  gen->callback([g] { run_gen(*g); });

  auto a = std::make_shared<AnalyzeArgs>();
  auto* cmd = app.add_subcommand(
      "paper", "Analyse a paper animation: friction and crumpling events and their resonators");
  cmd->add_option("animation", a->animation, "ANIMATION.json (docs/paper-format.md)")->required();
  cmd->add_option("--events", a->events, "Write the events and resonators per frame as JSON");
  cmd->add_option("-o,--output", a->output, "Synthesize the sound to this WAV (stereo, 44.1 kHz)");
  cmd->add_option("--db", a->db,
                  "Sound database folder (chladni paper-db generate); default: generated in "
                  "memory");
  cmd->add_option("--paper-mode", a->mode, "database | modal | both (database)");
  cmd->add_option("--backend", a->backend, "Filterbank of the modal voices: cpu | gpu (cpu)");
  cmd->add_option("--listener", a->listener, "Listener position X,Y,Z in metres")
      ->check(finite_in(-1e6, 1e6))
      ->delimiter(',')
      ->expected(3);
  add_spectrogram_options(*cmd, a->spectrogram);
  cmd->add_option("--seed", a->seed, "Random seed (variants, phases, clicks)");
  cmd->add_option("--ridge-angle", a->options.ridge_angle, "a_max (rad) of a ridge (0.5)")
      ->check(finite_above(0, 3.1416));
  cmd->add_option("--flat-curvature", a->options.flat_curvature,
                  "Curvature (1/m) below which a face is flat (2)")
      ->check(finite_above(0, 1e9));
  cmd->add_option("--crumple-curvature", a->options.crumple_curvature,
                  "|mean curvature| (1/m) that establishes a sign (1)")
      ->check(finite_above(0, 1e9));
  cmd->callback([a] { run_analyze(*a); });

  auto* db =
      app.add_subcommand("paper-db", "Paper sound databases: generate the default, inspect one");
  db->require_subcommand(1);
  auto d = std::make_shared<DbArgs>();
  auto* dgen = db->add_subcommand("generate", "Generate the default database from the sheet model");
  dgen->add_option("-o,--output", d->dir, "Database folder to write")->required();
  dgen->add_option("--seed", d->options.seed, "Random seed (1)");
  dgen->add_option("--variants", d->options.variants, "Clips and spectra per entry (3)")
      ->check(CLI::Range(1, 16));
  dgen->add_option("--young", d->options.material.young, "Young's modulus of the paper, Pa (4e9)")
      ->check(finite_in(1e8, 1e11));
  dgen->add_option("--loss-factor", d->options.material.loss_factor,
                   "Structural loss factor (0.04)")
      ->check(finite_above(0, 1));
  dgen->add_option("--clip-seconds", d->options.clip_seconds, "Crumple clip length (0.25)")
      ->check(finite_above(0, 2));
  dgen->add_option("--friction-seconds", d->friction_seconds,
                   "Length of each friction recording written (1)")
      ->check(finite_above(0.1, 30));
  dgen->add_option("--surfaces", d->options.surfaces, "Friction surface names (wood)");
  dgen->callback([d] { run_db_generate(*d); });
  auto* dinfo = db->add_subcommand("info", "Summarize a database folder");
  dinfo->add_option("dir", d->dir, "Database folder")->required();
  dinfo->callback([d] { run_db_info(*d); });
}

}  // namespace chladni::cli
