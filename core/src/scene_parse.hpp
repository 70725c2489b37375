#pragma once
// What the scene's event parsers share (scene.cpp, scene_contact.cpp).
#include "chladni/core/json_reader.hpp"
#include "chladni/core/scene.hpp"

namespace chladni::scene_parse {

/// A render holds its whole output in memory, so a scene lasts at most an hour.
constexpr double kMaxSceneSeconds = 3600;

/// The event's `time`, within the scene's hour.
double event_time(json_reader::Obj& o);
/// The index of the object named by `key`.
std::size_t find_object(json_reader::Obj& o, const Scene& scene, const std::string& key = "object");

ContactEvent parse_contact(json_reader::Obj o, const Scene& scene);

}  // namespace chladni::scene_parse
