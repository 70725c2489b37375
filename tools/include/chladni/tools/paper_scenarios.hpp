#pragma once
// Procedural paper animations for examples, tests and benchmarks (docs/paper-format.md):
// "slide" (a sheet slid on a table while its front edge is pushed so it curls up, the paper's
// Figure 1), "shake" (held by two corners and shaken, Figure 17), "flap" (a bent sheet whose
// curvature snaps back and forth) and "crumple" (bumps that grow and snap, progressively).
// Kinematic, not simulated: each records the frames where its events happen, so the analysis
// and the synthesis can be checked against them.
#include <cstdint>
#include <string>
#include <vector>

#include "chladni/core/paper_animation.hpp"

namespace chladni::tools {

struct PaperScenarioOptions {
  std::uint32_t triangles = 800;  ///< approximate; the grid rounds it
  double frame_rate = 60;
  double duration = 0;  ///< s; 0 = the scenario's own
  std::uint32_t seed = 1;
};

struct PaperScenario {
  PaperAnimation animation;
  /// Frames at which a crumpling snap completes (flap, shake, crumple) or, for slide, the
  /// first and last frames of sliding.
  std::vector<std::uint32_t> event_frames;
  double sheet_width = 0, sheet_length = 0;  ///< m
  std::string description;
};

std::vector<std::string> paper_scenario_names();
/// Throws InputError for an unknown name or options out of range.
PaperScenario make_paper_scenario(const std::string& name, const PaperScenarioOptions& options);

}  // namespace chladni::tools
