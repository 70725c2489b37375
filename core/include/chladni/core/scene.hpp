#pragma once
// The scene a render plays: objects, a listener and timed events (docs/scene-format.md).
// Parsing validates everything and names the JSON path of the first problem.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "chladni/core/damping.hpp"
#include "chladni/core/modal_model.hpp"

namespace chladni {

/// Unit quaternion (w, x, y, z) rotating object coordinates into world coordinates.
using Quat = std::array<double, 4>;
/// q v q*: object frame to world frame.
Vec3 rotate(const Quat& q, const Vec3& v);
/// q* v q: world frame to object frame.
Vec3 rotate_inverse(const Quat& q, const Vec3& v);

struct Listener {
  Vec3 position{0, 0, 0};
  Vec3 forward{0, 1, 0};
  Vec3 up{0, 0, 1};
};

struct InlineMode {
  double frequency = 0;  ///< Hz (damped)
  double decay = 0;      ///< 1/s
  double amplitude = 0;  ///< Pa at 1 m per N*s of impulse
};

/// A free-free rectangular bar described analytically (Euler-Bernoulli bending + axial modes).
struct BarSpec {
  double length = 0.3, width = 0.03, thickness = 0.01;  ///< m (x, y, z)
  double youngs_modulus = 200e9, poisson_ratio = 0.29, density = 7850;
  DampingModel damping{DampingModel::Kind::Rayleigh, {2.0, 2e-9}};
  double max_frequency = 20000;  ///< Hz
};

struct SceneObject {
  enum class Source { Modes, Bar, Soundbank };
  std::string name;
  std::string json_path;  ///< "$.objects[i]", for messages
  Source source = Source::Modes;
  std::vector<InlineMode> modes;
  BarSpec bar;
  std::string soundbank;  ///< path resolved against the scene file's folder
  Vec3 position{0, 0, 0};
  Quat orientation{1, 0, 0, 0};  ///< object frame -> world frame
  double gain = 1.0;
};

struct ImpactEvent {
  std::string json_path;
  double time = 0;           ///< s
  std::size_t object = 0;    ///< index into Scene::objects
  double impulse = 0;        ///< N*s
  Vec3 direction{0, 0, -1};  ///< unit, object frame
  std::optional<Vec3> point;
  std::optional<std::size_t> vertex;
  double contact_time = 0;  ///< s; 0 = ideal impulse, else half-sine force of this duration
};

/// The listener or an object moves (jumps) to a new pose at `time`; gains from acoustic transfer
/// and panning are recomputed there.
struct MoveEvent {
  std::string json_path;
  double time = 0;
  std::optional<std::size_t> object;  ///< none: the listener moves
  std::optional<Vec3> position;
  std::optional<Quat> orientation;  ///< objects
  std::optional<Vec3> forward, up;  ///< listener
};

/// Particles shaken against an object (PhISEM, runtime/phisem.hpp): the instrument's particle
/// process drives the object's modes ("gravel in a bowl"), or, with resonate = instrument, the
/// instrument's own resonances placed at the object. Shakes with the same object, instrument,
/// resonance choice and particle count share one voice.
struct ShakeEvent {
  std::string json_path;
  double time = 0;
  std::size_t object = 0;
  std::string instrument;
  double energy = 0.5;   ///< (0, 1]
  double particles = 0;  ///< 0: the instrument's own count
  bool resonate_object = true;
  double impulse = 1e-3;  ///< N*s per unit of excitation on the object's surface
};

/// The surface a contact traverses: a named preset (runtime/contact/surface_profile.hpp) and
/// any fields overriding it.
struct RoughnessSpec {
  std::string surface = "steel";
  std::optional<double> level, height, beta, shortest, longest, patch, ribs, rib_depth;
};

/// A continuous contact (sliding, rolling) on an object, optionally pressed against a second
/// one: a trajectory of `samples` values at `rate` per second from `time` on, each field one
/// value per sample or one for all (docs/scene-format.md).
struct ContactEvent {
  std::string json_path;
  double time = 0;
  std::size_t object = 0;
  std::optional<std::size_t> other;
  double rate = 100;                     ///< trajectory samples per second
  std::size_t samples = 0;               ///< >= 2
  std::vector<double> force;             ///< N (1 or `samples` values)
  std::vector<double> slip, rolling;     ///< m/s (1 or `samples` values)
  std::vector<Vec3> point, other_point;  ///< object frames (empty: the first surface point)
  RoughnessSpec roughness;
  double end_time() const { return time + double(samples - 1) / rate; }
};

struct Scene {
  int sample_rate = 48000;
  int channels = 2;
  std::optional<double> duration;  ///< s; default: last event plus the longest ring-out
  double gain = 1.0;
  Listener listener;
  std::vector<SceneObject> objects;
  std::vector<ImpactEvent> events;     ///< sorted by time
  std::vector<MoveEvent> moves;        ///< sorted by time
  std::vector<ShakeEvent> shakes;      ///< sorted by time
  std::vector<ContactEvent> contacts;  ///< sorted by time
};

/// Parses a scene from JSON; `base_dir` resolves relative file names. Throws InputError whose
/// message starts with the JSON path of the problem ("$.events[2].time: must be >= 0").
Scene parse_scene(const nlohmann::json& j, const std::string& base_dir);

/// Reads and parses a scene file; syntax errors name the file, line and column.
Scene load_scene(const std::string& path);

}  // namespace chladni
