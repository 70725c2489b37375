// chladni paper-gen NAME -o DIR: the procedural example animations.
// chladni paper ANIMATION.json --events OUT.json: the per-frame analysis (events, resonators).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "chladni/core/error.hpp"
#include "chladni/core/paper_animation.hpp"
#include "chladni/runtime/paper_analysis.hpp"
#include "chladni/runtime/paper_scenarios.hpp"
#include "commands.hpp"

namespace chladni::cli {
namespace {

struct GenArgs {
  std::string name, dir;
  runtime::PaperScenarioOptions options;
  bool binary = false;
};

void run_gen(const GenArgs& a) {
  std::vector<std::string> names{a.name};
  if (a.name == "all") names = runtime::paper_scenario_names();
  std::filesystem::create_directories(a.dir);
  for (const std::string& n : names) {
    const runtime::PaperScenario s = runtime::make_paper_scenario(n, a.options);
    const std::string path = (std::filesystem::path(a.dir) / (n + ".json")).string();
    write_paper_animation(path, s.animation,
                          a.binary ? PaperFrameStorage::Binary : PaperFrameStorage::Obj);
    std::printf("wrote %s: %u triangles, %u frames at %g fps (%s)\n", path.c_str(),
                unsigned(s.animation.triangles.size()), s.animation.frame_count(),
                s.animation.frame_rate, s.description.c_str());
  }
}

struct AnalyzeArgs {
  std::string animation, events;
  runtime::PaperAnalysisOptions options;
};

nlohmann::json resonator_json(const runtime::PaperResonator& r) {
  return {{"curved", r.curved},       {"constrained", r.constrained}, {"faces", r.faces},
          {"area_m2", r.area},        {"centroid", r.centroid},       {"normal", r.normal},
          {"l_r_m", r.ruling_length}, {"l_c_m", r.free_border}};
}

void run_analyze(const AnalyzeArgs& a) {
  const PaperAnimation anim = load_paper_animation(a.animation);
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
    std::ofstream out(a.events);
    out << nlohmann::json{{"animation", a.animation},
                          {"frame_rate", anim.frame_rate},
                          {"frames", anim.frame_count()},
                          {"ms_per_frame", 1e3 * seconds / anim.frame_count()},
                          {"event_frames", std::move(frames)}}
               .dump(1)
        << "\n";
    if (!out) throw InputError("cannot write " + a.events);
    std::printf("wrote %s\n", a.events.c_str());
  }
}

}  // namespace

void add_paper(CLI::App& app) {
  auto g = std::make_shared<GenArgs>();
  auto* gen = app.add_subcommand(
      "paper-gen", "Write a procedural paper animation (slide, shake, flap, crumple or all)");
  gen->add_option("name", g->name, "Scenario: slide, shake, flap, crumple or all")->required();
  gen->add_option("-o,--output", g->dir, "Folder for NAME.json and its frames")->required();
  gen->add_option("--triangles", g->options.triangles, "Approximate triangle count (800)");
  gen->add_option("--duration", g->options.duration, "Seconds (default: the scenario's)");
  gen->add_option("--frame-rate", g->options.frame_rate, "Frames per second (60)");
  gen->add_option("--seed", g->options.seed, "Random seed (crumple)");
  gen->add_flag("--binary", g->binary, "Store frames as one .chpaper file instead of OBJs");
  gen->callback([g] { run_gen(*g); });

  auto a = std::make_shared<AnalyzeArgs>();
  auto* cmd = app.add_subcommand(
      "paper", "Analyse a paper animation: friction and crumpling events and their resonators");
  cmd->add_option("animation", a->animation, "ANIMATION.json (docs/paper-format.md)")->required();
  cmd->add_option("--events", a->events, "Write the events and resonators per frame as JSON");
  cmd->add_option("--ridge-angle", a->options.ridge_angle, "a_max (rad) of a ridge (0.5)");
  cmd->add_option("--flat-curvature", a->options.flat_curvature,
                  "Curvature (1/m) below which a face is flat (2)");
  cmd->add_option("--crumple-curvature", a->options.crumple_curvature,
                  "|mean curvature| (1/m) that establishes a sign (1)");
  cmd->callback([a] { run_analyze(*a); });
}

}  // namespace chladni::cli
