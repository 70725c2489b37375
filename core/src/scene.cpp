#include "chladni/core/scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <sstream>

#include "chladni/core/error.hpp"
#include "chladni/core/json_reader.hpp"
#include "scene_parse.hpp"

namespace chladni {
namespace {

using json_reader::fail;
using json_reader::index_path;
using json_reader::Obj;
using json_reader::read_json_file;
using nlohmann::json;

using scene_parse::event_time;
using scene_parse::find_object;
using scene_parse::kMaxSceneSeconds;

void parse_bar(Obj o, BarSpec& bar) {
  bar.length = o.positive("length", bar.length);
  bar.width = o.positive("width", bar.width);
  bar.thickness = o.positive("thickness", bar.thickness);
  bar.youngs_modulus = o.positive("youngs_modulus", bar.youngs_modulus);
  bar.poisson_ratio = o.number("poisson_ratio", bar.poisson_ratio);
  if (!(bar.poisson_ratio > -1.0 && bar.poisson_ratio < 0.5)) {
    fail(o.at("poisson_ratio"), "must lie in (-1, 0.5)");
  }
  bar.density = o.positive("density", bar.density);
  bar.max_frequency = o.positive("max_frequency", bar.max_frequency);
  if (o.has("damping")) {
    try {
      bar.damping = DampingModel::parse(o.string("damping"));
    } catch (const InputError& e) {
      fail(o.at("damping"), e.what());
    }
  }
  o.done();
}

SceneObject parse_object(Obj o, const std::string& base_dir) {
  SceneObject obj;
  obj.json_path = o.path();
  obj.name = o.string("name");
  if (obj.name.empty()) fail(o.at("name"), "must not be empty");
  if (o.has("position")) obj.position = o.vec3("position");
  if (o.has("orientation")) obj.orientation = o.quaternion("orientation");
  obj.gain = o.non_negative("gain", 1.0);
  const int sources = int(o.has("modes")) + int(o.has("bar")) + int(o.has("soundbank"));
  if (sources != 1) fail(o.path(), "needs exactly one of 'modes', 'bar' or 'soundbank'");
  if (o.has("modes")) {
    obj.source = SceneObject::Source::Modes;
    const json& modes = o.array("modes");
    if (modes.empty()) fail(o.at("modes"), "must not be empty");
    for (std::size_t i = 0; i < modes.size(); ++i) {
      Obj m(modes[i], index_path(o.at("modes"), i));
      InlineMode im;
      im.frequency = m.number("frequency");
      if (!(im.frequency > 0)) fail(m.at("frequency"), "must be > 0");
      im.decay = m.number("decay");
      if (im.decay < 0) fail(m.at("decay"), "must be >= 0");
      im.amplitude = m.number("amplitude");
      m.done();
      obj.modes.push_back(im);
    }
  } else if (o.has("bar")) {
    obj.source = SceneObject::Source::Bar;
    parse_bar(Obj(o.get("bar"), o.at("bar")), obj.bar);
  } else {
    obj.source = SceneObject::Source::Soundbank;
    const std::filesystem::path p(o.string("soundbank"));
    obj.soundbank = (p.is_absolute() ? p : std::filesystem::path(base_dir) / p).string();
  }
  o.done();
  return obj;
}

MoveEvent parse_move(Obj o, const Scene& scene, bool listener) {
  MoveEvent ev;
  ev.json_path = o.path();
  o.string("type");
  ev.time = event_time(o);
  if (o.has("position")) ev.position = o.vec3("position");
  if (listener) {
    if (o.has("forward")) ev.forward = o.unit("forward");
    if (o.has("up")) ev.up = o.unit("up");
    if (!ev.position && !ev.forward && !ev.up)
      fail(o.path(), "a listener event needs 'position', 'forward' or 'up'");
  } else {
    ev.object = find_object(o, scene);
    if (o.has("orientation")) ev.orientation = o.quaternion("orientation");
    if (!ev.position && !ev.orientation)
      fail(o.path(), "a move event needs 'position' or 'orientation'");
  }
  o.done();
  return ev;
}

// The fields every event on an object has: its path, type (already dispatched on), time, object.
template <class Event>
Event event_on_object(Obj& o, const Scene& scene) {
  Event ev;
  ev.json_path = o.path();
  o.string("type");
  ev.time = event_time(o);
  ev.object = find_object(o, scene);
  return ev;
}

ImpactEvent parse_event(Obj o, const Scene& scene) {
  ImpactEvent ev = event_on_object<ImpactEvent>(o, scene);
  ev.impulse = o.number("impulse");
  if (!(ev.impulse > 0)) fail(o.at("impulse"), "must be > 0");
  if (o.has("direction")) ev.direction = o.unit("direction");
  if (o.has("point") && o.has("vertex")) fail(o.path(), "give 'point' or 'vertex', not both");
  if (o.has("point")) ev.point = o.vec3("point");
  if (o.has("vertex")) {
    const long v = o.integer("vertex");
    if (v < 0) fail(o.at("vertex"), "must be >= 0");
    ev.vertex = static_cast<std::size_t>(v);
  }
  ev.contact_time = o.non_negative("contact_time", 0.0);
  if (ev.contact_time > 0.1) fail(o.at("contact_time"), "must be <= 0.1 s");
  o.done();
  return ev;
}

ShakeEvent parse_shake(Obj o, const Scene& scene) {
  ShakeEvent ev = event_on_object<ShakeEvent>(o, scene);
  ev.instrument = o.string("instrument");
  ev.energy = o.number("energy", 0.5);
  if (!(ev.energy > 0 && ev.energy <= 1)) fail(o.at("energy"), "must lie in (0, 1]");
  ev.particles = o.non_negative("particles", 0.0);
  if (ev.particles > 1e6) fail(o.at("particles"), "must be <= 1e6");
  if (o.has("resonate")) {
    const std::string r = o.string("resonate");
    if (r != "object" && r != "instrument")
      fail(o.at("resonate"), "must be 'object' or 'instrument', got '" + r + "'");
    ev.resonate_object = r == "object";
  }
  ev.impulse = o.positive("impulse", 1e-3);
  o.done();
  return ev;
}

}  // namespace

double scene_parse::event_time(Obj& o) {
  const double t = o.number("time");
  if (t < 0 || t > kMaxSceneSeconds)
    fail(o.at("time"), "must lie in [0, 3600] s (a scene lasts at most an hour)");
  return t;
}

std::size_t scene_parse::find_object(Obj& o, const Scene& scene, const std::string& key) {
  const std::string name = o.string(key);
  const auto it = std::find_if(scene.objects.begin(), scene.objects.end(),
                               [&](const SceneObject& s) { return s.name == name; });
  if (it == scene.objects.end()) fail(o.at(key), "unknown object '" + name + "'");
  return static_cast<std::size_t>(it - scene.objects.begin());
}

Vec3 rotate(const Quat& q, const Vec3& v) {
  // v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
  const Vec3 u{q[1], q[2], q[3]};
  const Vec3 t = cross(u, v);
  const Vec3 t2 = cross(u, t);
  return {v[0] + 2 * (q[0] * t[0] + t2[0]), v[1] + 2 * (q[0] * t[1] + t2[1]),
          v[2] + 2 * (q[0] * t[2] + t2[2])};
}

Vec3 rotate_inverse(const Quat& q, const Vec3& v) {
  return rotate({q[0], -q[1], -q[2], -q[3]}, v);
}

Scene parse_scene(const json& j, const std::string& base_dir) {
  Obj root(j, "$");
  Scene s;
  if (root.has("sample_rate")) {
    const long sr = root.integer("sample_rate");
    if (sr < 8000 || sr > 384000) fail(root.at("sample_rate"), "must lie in [8000, 384000]");
    s.sample_rate = static_cast<int>(sr);
  }
  if (root.has("channels")) {
    const long ch = root.integer("channels");
    if (ch != 1 && ch != 2) fail(root.at("channels"), "must be 1 or 2");
    s.channels = static_cast<int>(ch);
  }
  if (root.has("duration")) {
    s.duration = root.number("duration");
    if (!(*s.duration > 0) || *s.duration > kMaxSceneSeconds)
      fail(root.at("duration"), "must lie in (0, 3600] s");
  }
  s.gain = root.non_negative("gain", 1.0);
  if (root.has("listener")) {
    Obj l(root.get("listener"), root.at("listener"));
    if (l.has("position")) s.listener.position = l.vec3("position");
    if (l.has("forward")) s.listener.forward = l.unit("forward");
    if (l.has("up")) s.listener.up = l.unit("up");
    l.done();
    const Vec3 &f = s.listener.forward, &u = s.listener.up;
    const double c = f[0] * u[0] + f[1] * u[1] + f[2] * u[2];
    if (std::abs(c) > 0.999) fail(l.path(), "'forward' and 'up' must not be parallel");
  }
  const json& objects = root.array("objects");
  if (objects.empty()) fail(root.at("objects"), "must not be empty");
  for (std::size_t i = 0; i < objects.size(); ++i) {
    SceneObject obj = parse_object(Obj(objects[i], index_path("$.objects", i)), base_dir);
    for (const SceneObject& other : s.objects) {
      if (other.name == obj.name)
        fail(obj.json_path + ".name", "duplicate name '" + obj.name + "'");
    }
    s.objects.push_back(std::move(obj));
  }
  const json& events = root.array("events");
  for (std::size_t i = 0; i < events.size(); ++i) {
    const std::string path = index_path("$.events", i);
    Obj peek(events[i], path);
    const std::string type = peek.string("type");
    if (type == "impact")
      s.events.push_back(parse_event(Obj(events[i], path), s));
    else if (type == "move" || type == "listener")
      s.moves.push_back(parse_move(Obj(events[i], path), s, type == "listener"));
    else if (type == "shake")
      s.shakes.push_back(parse_shake(Obj(events[i], path), s));
    else if (type == "contact")
      s.contacts.push_back(scene_parse::parse_contact(Obj(events[i], path), s));
    else
      fail(peek.at("type"),
           "unknown event type '" + type + "' (known: impact, move, listener, shake, contact)");
  }
  root.done();
  std::stable_sort(s.events.begin(), s.events.end(),
                   [](const ImpactEvent& a, const ImpactEvent& b) { return a.time < b.time; });
  std::stable_sort(s.moves.begin(), s.moves.end(),
                   [](const MoveEvent& a, const MoveEvent& b) { return a.time < b.time; });
  std::stable_sort(s.shakes.begin(), s.shakes.end(),
                   [](const ShakeEvent& a, const ShakeEvent& b) { return a.time < b.time; });
  std::stable_sort(s.contacts.begin(), s.contacts.end(),
                   [](const ContactEvent& a, const ContactEvent& b) { return a.time < b.time; });
  for (const MoveEvent& m : s.moves) {
    if (m.object) continue;
    const Vec3 f = m.forward.value_or(s.listener.forward), u = m.up.value_or(s.listener.up);
    if (std::abs(f[0] * u[0] + f[1] * u[1] + f[2] * u[2]) > 0.999)
      fail(m.json_path, "'forward' and 'up' must not be parallel");
  }
  return s;
}

Scene load_scene(const std::string& path) {
  const json j = read_json_file(path, "scene");
  const std::string dir = std::filesystem::path(path).parent_path().string();
  try {
    return parse_scene(j, dir.empty() ? "." : dir);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
}

}  // namespace chladni
