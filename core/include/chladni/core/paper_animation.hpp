#pragma once
// An animated paper sheet: one triangle mesh with fixed topology and its vertex positions per
// frame, the anchored vertices (fingers), the planar obstacles it touches and the listener
// (docs/paper-format.md). Loading validates everything and names the file, frame, vertex or
// JSON path of the first problem.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "chladni/core/vec3.hpp"

namespace chladni {

/// Vertices held fixed (by fingers or clamps) over an inclusive range of frames.
struct PaperAnchor {
  std::vector<std::uint32_t> vertices;
  std::uint32_t first_frame = 0;
  std::uint32_t last_frame = 0;  ///< inclusive
};

/// An infinite rigid plane: a table or a wall. `friction` names the friction database entry
/// set used for sliding against it.
struct PaperObstacle {
  std::string name;
  Vec3 point{0, 0, 0};
  Vec3 normal{0, 0, 1};  ///< unit, pointing to the side the paper is on
  std::string friction = "wood";
};

struct PaperListener {
  Vec3 position{0, -0.5, 0.3};
  Vec3 forward{0, 1, 0};
  Vec3 up{0, 0, 1};
  double ear_distance = 0.18;  ///< m between the two ears
};

struct PaperAnimation {
  double frame_rate = 60;  ///< frames per second
  std::uint32_t vertex_count = 0;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<float> positions;  ///< frame-major: frame f, vertex v, axis k at (f*V + v)*3 + k
  std::vector<PaperAnchor> anchors;
  std::vector<PaperObstacle> obstacles;
  PaperListener listener;
  double contact_distance = 0.002;  ///< m: a vertex this close to an obstacle touches it
  /// Informational, from a generator: what happens and the frames where it placed events.
  /// The analysis never reads them; tests and users compare against them.
  std::string description;
  std::vector<std::uint32_t> event_frames;

  std::uint32_t frame_count() const {
    return vertex_count ? static_cast<std::uint32_t>(positions.size() / (3 * vertex_count)) : 0;
  }
  std::span<const float> frame(std::uint32_t f) const {
    return {positions.data() + std::size_t(f) * vertex_count * 3, std::size_t(vertex_count) * 3};
  }
  double duration() const { return frame_count() / frame_rate; }
  /// Whether vertex v is held by an anchor at frame f.
  bool anchored(std::uint32_t v, std::uint32_t f) const;
};

/// How `write_paper_animation` stores the frames.
enum class PaperFrameStorage { Obj, Binary };

/// Reads ANIMATION.json and the frames it references (OBJ sequence or .chpaper binary).
PaperAnimation load_paper_animation(const std::string& json_path);

/// Writes ANIMATION.json and, beside it, the frames: NAME_0000.obj ... in a folder NAME/ or one
/// NAME.chpaper file, where NAME is the JSON file's stem.
void write_paper_animation(const std::string& json_path, const PaperAnimation& anim,
                           PaperFrameStorage storage);

/// The compact binary frame file on its own (docs/paper-format.md).
void write_paper_frames_binary(const std::string& path, const PaperAnimation& anim);
/// Reads a .chpaper into `anim` (triangles, vertex count, positions).
void read_paper_frames_binary(const std::string& path, PaperAnimation& anim);

/// Checks counts, indices, finiteness and topology; throws InputError naming the problem.
void validate(const PaperAnimation& anim, const std::string& where);
/// The same for what does not depend on frames: the frame rate, triangles, obstacles, contact
/// distance and listener (a live sheet, whose frames come from a simulation).
void validate_sheet(const PaperAnimation& anim, const std::string& where);

}  // namespace chladni
