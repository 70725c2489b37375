#pragma once
// Per-frame analysis of an animated paper sheet (Schreck et al. 2016, §4): friction and
// crumpling events, the partition into flat and curved regions, and for each event the
// resonators it sets vibrating with their (l_r, l_c) parameters (§5).
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "chladni/core/paper_animation.hpp"
#include "chladni/runtime/paper/paper_mesh.hpp"

namespace chladni::runtime {

struct PaperAnalysisOptions {
  double ridge_angle = 0.5;  ///< a_max (rad): edges folded more than this stop vibrations
  /// Faces whose larger principal curvature is below this (1/m; radius 0.5 m) are flat.
  double flat_curvature = 2.0;
  /// |H| (1/m) a vertex's mean curvature must exceed for its sign to count: a crumple is a
  /// change between signs established beyond it (below it the sign is noise).
  double crumple_curvature = 1.0;
  /// Friction events slower than this (m/s, mean tangential speed) are dropped.
  double min_friction_speed = 1e-3;
  int rulings_per_resonator = 8;  ///< rulings traced to estimate l_r
  /// Pieces smaller than this (m^2) are fragments of the flat/curved classification where the
  /// curvature hovers at the threshold, not resonators: dropped (1 cm^2; the paper's smallest
  /// database sheet is 2.5 x 1.25 cm).
  double min_resonator_area = 1e-4;
};

enum class PaperEventType { Friction, Crumple };

/// A region set vibrating by an event: a connected piece of one flat or curved region.
struct PaperResonator {
  bool curved = false;
  bool constrained = true;  ///< no free border: l_c == 0
  std::uint32_t faces = 0;
  double area = 0;           ///< m^2
  Vec3 centroid{0, 0, 0};    ///< m
  Vec3 normal{0, 0, 1};      ///< unit, area-weighted mean
  double ruling_length = 0;  ///< l_r (m): median length of the traced rulings (curved only)
  double free_border = 0;    ///< l_c (m): summed length of free curved borders
};

struct PaperEvent {
  PaperEventType type = PaperEventType::Friction;
  /// Friction: mean tangential speed of the contact (m/s). Crumple: sum over the event's
  /// vertices of |H_now - H_prev| (1/m).
  double amplitude = 0;
  std::int32_t obstacle = -1;  ///< friction: index into the animation's obstacles
  std::uint32_t vertices = 0;
  Vec3 centroid{0, 0, 0};
  std::vector<PaperResonator> resonators;
};

struct PaperFrameAnalysis {
  std::uint32_t frame = 0;
  double time = 0;  ///< s
  std::vector<PaperEvent> events;
  std::uint32_t regions = 0;  ///< flat + curved regions in the partition (0 when no event)
};

/// Analyses frames in order; keeps the previous frame's state. Buffers are reused, so after
/// the first frames the analysis of a frame allocates only for the events it returns.
class PaperAnalyzer {
 public:
  PaperAnalyzer(const PaperAnimation& anim, PaperAnalysisOptions options = {});
  /// Frame f must follow the previous call's frame by one (or be 0 to restart).
  PaperFrameAnalysis analyze(std::uint32_t frame);
  /// The same for positions given by the caller (3 floats per vertex), frames arriving one at a
  /// time from a live simulation: the animation supplies the sheet, obstacles and frame rate.
  /// `held`, when given, replaces the animation's anchors for this frame (InputError on an index
  /// past the sheet's vertices, or a position count that is not the sheet's).
  PaperFrameAnalysis analyze(std::uint32_t frame, std::span<const float> xyz,
                             const std::vector<std::uint32_t>* held = nullptr);
  const PaperTopology& topology() const { return topo_; }
  const PaperGeometry& geometry() const { return geo_; }
  /// Region id per face from the last analysed frame with events.
  const std::vector<std::int32_t>& face_region() const { return region_; }

 private:
  void partition();
  void detect_friction(std::uint32_t frame, std::vector<PaperEvent>& out);
  void detect_crumpling(std::vector<PaperEvent>& out);
  void find_resonators(const std::vector<std::uint32_t>& event_vertices, PaperEvent& ev);
  double trace_ruling(std::uint32_t face) const;
  std::uint32_t next_stamp();
  // The connected vertices from `seed` (marked in mark_) for which in_set holds, into members_.
  template <class Pred>
  void collect_vertices(std::uint32_t seed, Pred&& in_set);

  const PaperAnimation& anim_;
  PaperAnalysisOptions opt_;
  PaperTopology topo_;
  PaperGeometry geo_;
  std::vector<Vec3> prev_position_;
  std::vector<double> settled_curvature_;  // last mean curvature beyond the threshold, or 0
  std::int64_t last_frame_ = -1;
  // Scratch, reused across frames.
  std::vector<std::uint8_t> constrained_;  // per vertex: anchored or touching
  std::vector<std::uint8_t> barrier_;      // per edge
  std::vector<std::int32_t> region_;       // per face
  std::vector<std::uint8_t> curved_;       // per face
  std::vector<std::int32_t> mark_;         // per vertex or face, flood labels
  std::vector<std::uint32_t> flood_;       // per face: flood component (faces joined by open edges)
  std::vector<std::uint32_t> comp_start_, comp_faces_;  // CSR: faces of each component
  std::vector<std::uint32_t> comp_stamp_, reach_stamp_, piece_stamp_, comps_, reached_list_;
  std::uint32_t stamp_ = 0;
  // Resonators already found this frame, by the sorted flood components that produced them.
  std::vector<std::pair<std::vector<std::uint32_t>, std::vector<PaperResonator>>> cache_;
  std::vector<std::int32_t> piece_of_;  // per face: label of the last resonator piece holding it
  std::int32_t piece_label_ = 0;
  std::vector<std::uint32_t> stack_, members_, faces_;
  std::vector<double> lengths_;
  std::uint32_t region_count_ = 0;
  bool partitioned_ = false;
};

}  // namespace chladni::runtime
