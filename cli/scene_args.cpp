#include "scene_args.hpp"

#include <cstdio>

#include "commands.hpp"
#include "parse_choices.hpp"

namespace chladni::cli {

runtime::PreparedScene prepare(const Scene& scene, const SceneArgs& a) {
  runtime::SceneSettings s;
  s.filterbank.backend = parse_backend(a.backend, "--backend");
  s.filterbank.isa = parse_isa(a.isa);
  s.filterbank.threads = a.threads;
  s.filterbank.gain_ramp = a.gain_ramp;
  s.filterbank.pipelined = a.live;
  s.filterbank.warn = warn;
  s.block = a.block;
  s.max_modes = a.max_modes;
  s.retire_db = a.retire_db;
  runtime::PreparedScene p = runtime::prepare_scene(scene, s);
  if (!a.quiet)
    for (std::size_t k = 0; k < p.playable.size(); ++k)
      std::printf("  %-12s %s\n", scene.objects[k].name.c_str(), p.playable[k].summary.c_str());
  return p;
}

void add_scene_options(CLI::App& cmd, SceneArgs& a) {
  cmd.add_option("--backend", a.backend, "Filterbank: cpu or gpu (gpu falls back to cpu)")
      ->capture_default_str();
  cmd.add_option("--block", a.block, "Frames per filterbank call")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  cmd.add_option("--gain-ramp", a.gain_ramp,
                 "Samples over which listener and pose changes ramp the gains (0: at once)")
      ->check(CLI::Range(0, 65536))
      ->capture_default_str();
  cmd.add_option("--threads", a.threads, "CPU threads (0: all)")
      ->check(thread_count())
      ->capture_default_str();
  cmd.add_option("--isa", a.isa, "CPU instruction set: auto, scalar, avx2, avx512")
      ->capture_default_str();
  cmd.add_option("--max-modes", a.max_modes, "Resident mode budget (0: all modes of the scene)")
      ->check(CLI::Range(0, 1 << 24));
  cmd.add_option("--retire-db", a.retire_db, "Retire modes this far below their peak (dB)")
      ->check(finite_in(-400, 0))
      ->capture_default_str();
  cmd.add_flag("-q,--quiet", a.quiet, "Print nothing but errors");
}

}  // namespace chladni::cli
