// Paper-sound speed (docs/PERFORMANCE.md, "Paper sound"): per-frame event detection and
// resonator estimation (Schreck et al. 2016, §4) alone, then analysis plus synthesis per frame
// and the whole render's speed against real time in each synthesis mode (database; modal
// voices on the CPU filterbank; with --gpu also on the Vulkan one), on the generated
// scenarios at the paper's sheet sizes (183, 446 and 1,333 triangles, its Table 2) and at
// 20,000 triangles.
// Usage: chladni_paper_bench [--triangles 183,446,1333,20000] [--repeat N] [--gpu] [--json OUT]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>

#include "bench_support.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/paper/paper_analysis.hpp"
#include "chladni/runtime/paper/paper_synth.hpp"
#include "chladni/tools/paper_db_generate.hpp"
#include "chladni/tools/paper_scenarios.hpp"

using namespace chladni;

namespace {

using bench::clock_type;

double ms_since(clock_type::time_point t0) {
  return 1e3 * bench::seconds_since(t0);
}

struct Args {
  std::vector<std::uint32_t> sizes = {183, 446, 1333, 20000};
  std::string json;
  int repeat = 3;
  bool gpu = false;
};

// Throws std::invalid_argument with the message to print.
Args parse_args(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; i += 2) {
    if (!std::strcmp(argv[i], "--gpu")) {
      a.gpu = true;
      --i;
      continue;
    }
    if (i + 1 >= argc)
      throw std::invalid_argument(std::string("option ") + argv[i] + " needs a value");
    if (!std::strcmp(argv[i], "--triangles")) {
      a.sizes.clear();
      std::stringstream ss(argv[i + 1]);
      for (std::string tok; std::getline(ss, tok, ',');)
        a.sizes.push_back(std::uint32_t(std::stoul(tok)));
    } else if (!std::strcmp(argv[i], "--repeat")) {
      a.repeat = std::max(1, std::atoi(argv[i + 1]));
    } else if (!std::strcmp(argv[i], "--json")) {
      a.json = argv[i + 1];
    } else {
      throw std::invalid_argument(std::string("unknown option ") + argv[i]);
    }
  }
  return a;
}

// Event detection and resonator estimation alone, per frame: best of `repeat` passes (the
// analysis is deterministic, the machine is not).
nlohmann::json analysis_row(const std::string& name, const PaperAnimation& a, int repeat) {
  std::vector<double> best(a.frame_count(), 1e30);
  std::size_t events = 0, resonators = 0;
  std::vector<bool> has_event(a.frame_count(), false);
  for (int r = 0; r < repeat; ++r) {
    runtime::PaperAnalyzer an(a);
    for (std::uint32_t f = 0; f < a.frame_count(); ++f) {
      const auto t0 = clock_type::now();
      const auto fa = an.analyze(f);
      best[f] = std::min(best[f], ms_since(t0));
      if (r == 0) {
        events += fa.events.size();
        for (const auto& e : fa.events) resonators += e.resonators.size();
        has_event[f] = !fa.events.empty();
      }
    }
  }
  double mean = 0, worst = 0, event_mean = 0;
  std::size_t event_frames = 0;
  for (std::uint32_t f = 0; f < a.frame_count(); ++f) {
    mean += best[f], worst = std::max(worst, best[f]);
    if (has_event[f]) event_mean += best[f], ++event_frames;
  }
  mean /= a.frame_count();
  event_mean = event_frames ? event_mean / double(event_frames) : 0;
  std::printf("%-8s %9zu %7u | %12.3f %12.3f %14.3f | %7zu %10zu\n", name.c_str(),
              a.triangles.size(), a.frame_count(), mean, worst, event_mean, events, resonators);
  return {{"scenario", name},          {"triangles", a.triangles.size()},
          {"frames", a.frame_count()}, {"mean_ms", mean},
          {"max_ms", worst},           {"event_frame_mean_ms", event_mean},
          {"events", events},          {"resonators", resonators}};
}

// Analysis plus synthesis per frame (best of `repeat` per frame) and the whole render, with the
// database (fb null) or modal voices on `fb`.
nlohmann::json synthesis_row(const std::string& name, const PaperAnimation& a,
                             const runtime::PaperSoundDb& db, const std::string& mode,
                             runtime::Filterbank* fb, int repeat) {
  runtime::PaperSynthOptions o;
  o.mode = fb ? runtime::PaperSynthMode::Modal : runtime::PaperSynthMode::Database;
  std::vector<double> best(a.frame_count(), 1e30);
  double best_wall = 1e30, audio = 0;
  std::uint32_t voices = 0;
  for (int r = 0; r < repeat; ++r) {
    const auto w0 = clock_type::now();
    runtime::PaperRenderer pr(a, &db, fb, o);
    for (std::uint32_t f = 0; f < a.frame_count(); ++f) {
      const auto t0 = clock_type::now();
      pr.step();
      best[f] = std::min(best[f], ms_since(t0));
    }
    pr.finish();
    best_wall = std::min(best_wall, 1e-3 * ms_since(w0));
    audio = pr.report().audio_seconds;
    voices = pr.report().peak_modal_voices;
  }
  double mean = 0, worst = 0;
  for (double b : best) mean += b, worst = std::max(worst, b);
  mean /= a.frame_count();
  std::printf("%-8s %9zu %-10s | %10.3f %10.3f | %8.0f %10u\n", name.c_str(), a.triangles.size(),
              mode.c_str(), mean, worst, audio / best_wall, voices);
  return {{"scenario", name},
          {"triangles", a.triangles.size()},
          {"mode", mode},
          {"frame_mean_ms", mean},
          {"frame_max_ms", worst},
          {"realtime_factor", audio / best_wall},
          {"peak_modal_voices", voices}};
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = bench::parse_or_exit(parse_args, argc, argv);
  const auto g0 = clock_type::now();
  const runtime::PaperSoundDb db = tools::generate_paper_database({});
  std::printf("default database generated in %.2f s\n", 1e-3 * ms_since(g0));
  runtime::CpuFilterbankOptions co;
  co.channels = 2;
  co.capacity = 1u << 18;
  co.max_frames = 1024;
  runtime::CpuFilterbank cpu(co);
  std::unique_ptr<runtime::GpuFilterbank> gpu;
  if (args.gpu) {
    runtime::GpuFilterbankOptions go;
    go.channels = 2;
    go.capacity = 1u << 18;
    go.max_frames = 1024;
    gpu = std::make_unique<runtime::GpuFilterbank>(std::make_shared<gpu::Context>(), go);
    std::printf("gpu: %s\n", gpu->name().c_str());
  }
  // Each scenario and size once, for both tables (the 20k ones take a while to generate).
  std::vector<std::pair<std::string, tools::PaperScenario>> scenarios;
  for (const std::string& name : tools::paper_scenario_names())
    for (std::uint32_t tris : args.sizes) {
      tools::PaperScenarioOptions o;
      o.triangles = tris;
      scenarios.emplace_back(name, tools::make_paper_scenario(name, o));
    }
  nlohmann::json rows = nlohmann::json::array(), synth_rows = nlohmann::json::array();
  std::printf("%-8s %9s %7s | %12s %12s %14s | %7s %10s\n", "scenario", "triangles", "frames",
              "mean ms", "max ms", "event-frame ms", "events", "resonators");
  for (const auto& [name, s] : scenarios)
    rows.push_back(analysis_row(name, s.animation, args.repeat));
  std::printf("\n%-8s %9s %-10s | %10s %10s | %8s %10s\n", "scenario", "triangles", "mode",
              "mean ms", "max ms", "x realtime", "voices");
  for (const auto& [name, s] : scenarios) {
    std::vector<std::pair<std::string, runtime::Filterbank*>> modes = {{"database", nullptr},
                                                                       {"modal-cpu", &cpu}};
    if (gpu) modes.push_back({"modal-gpu", gpu.get()});
    for (const auto& [mode, fb] : modes)
      synth_rows.push_back(synthesis_row(name, s.animation, db, mode, fb, args.repeat));
  }
  if (!args.json.empty())
    std::ofstream(args.json) << nlohmann::json{{"analysis", rows}, {"synthesis", synth_rows}}.dump(
                                    1)
                             << "\n";
  return 0;
}
