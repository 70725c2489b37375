// Contact events: a trajectory of normal force, slip and rolling speed and contact points.
#include <cmath>
#include <string>

#include "scene_parse.hpp"

namespace chladni::scene_parse {
namespace {

using json_reader::fail;
using json_reader::Obj;
using nlohmann::json;

// A contact's trajectory holds at most this many samples (a scene's hour at 250 per second).
constexpr std::size_t kMaxContactSamples = 1u << 20;
constexpr double kMaxForce = 1e6, kMaxSpeed = 100;

// `key` as one number for every sample or an array of them; each in [0, max].
std::vector<double> numbers(Obj& o, const std::string& key, double max, bool required) {
  if (!o.has(key)) {
    if (required) o.get(key);  // names the missing field
    return {0.0};
  }
  const json& v = o.get(key);
  std::vector<double> out;
  auto take = [&](const json& x, const std::string& path) {
    if (!x.is_number()) fail(path, std::string("expected a number, got ") + x.type_name());
    const double d = x.get<double>();
    if (!(std::isfinite(d) && d >= 0 && d <= max))
      fail(path, "must lie in [0, " + json(max).dump() + "]");
    out.push_back(d);
  };
  if (v.is_array()) {
    if (v.empty() || v.size() > kMaxContactSamples)
      fail(o.at(key), "must hold 1 to " + std::to_string(kMaxContactSamples) + " values");
    for (std::size_t i = 0; i < v.size(); ++i) take(v[i], json_reader::index_path(o.at(key), i));
  } else {
    take(v, o.at(key));
  }
  return out;
}

// `key` as one point ([x, y, z]) or an array of them.
std::vector<Vec3> points(Obj& o, const std::string& key) {
  if (!o.has(key)) return {};
  const json& v = o.get(key);
  if (v.is_array() && !v.empty() && v[0].is_number()) return {o.vec3(key)};
  if (!v.is_array() || v.empty() || v.size() > kMaxContactSamples)
    fail(o.at(key), "expected [x, y, z] or an array of them");
  std::vector<Vec3> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const std::string path = json_reader::index_path(o.at(key), i);
    if (!v[i].is_array() || v[i].size() != 3) fail(path, "expected an array of 3 numbers");
    Vec3 p{};
    for (int k = 0; k < 3; ++k) {
      if (!v[i][k].is_number() || !std::isfinite(v[i][k].get<double>()))
        fail(path + "[" + std::to_string(k) + "]", "expected a finite number");
      p[k] = v[i][k].get<double>();
    }
    out.push_back(p);
  }
  return out;
}

void parse_roughness(Obj o, RoughnessSpec& r) {
  if (o.has("surface")) r.surface = o.string("surface");
  const std::pair<const char*, std::optional<double>*> fields[] = {
      {"level", &r.level},       {"height", &r.height},      {"beta", &r.beta},
      {"shortest", &r.shortest}, {"longest", &r.longest},    {"patch", &r.patch},
      {"ribs", &r.ribs},         {"rib_depth", &r.rib_depth}};
  for (const auto& [key, field] : fields)
    if (o.has(key)) *field = o.non_negative(key, 0);
  o.done();
}

}  // namespace

ContactEvent parse_contact(Obj o, const Scene& scene) {
  ContactEvent ev;
  ev.json_path = o.path();
  o.string("type");
  ev.time = event_time(o);
  ev.object = find_object(o, scene);
  if (o.has("other")) {
    ev.other = find_object(o, scene, "other");
    if (*ev.other == ev.object) fail(o.at("other"), "must name another object");
  }
  ev.rate = o.positive("rate", 100);
  if (ev.rate > 48000) fail(o.at("rate"), "must be <= 48000 samples per second");
  ev.force = numbers(o, "force", kMaxForce, true);
  ev.slip = numbers(o, "slip", kMaxSpeed, false);
  ev.rolling = numbers(o, "rolling", kMaxSpeed, false);
  ev.point = points(o, "point");
  ev.other_point = points(o, "other_point");
  if (!ev.other && o.has("other_point")) fail(o.at("other_point"), "needs 'other'");
  if (o.has("roughness")) parse_roughness(Obj(o.get("roughness"), o.at("roughness")), ev.roughness);
  // Every per-sample field has one length; a contact of constants needs its duration.
  std::size_t n = 1;
  const std::pair<const char*, std::size_t> sizes[] = {{"force", ev.force.size()},
                                                       {"slip", ev.slip.size()},
                                                       {"rolling", ev.rolling.size()},
                                                       {"point", ev.point.size()},
                                                       {"other_point", ev.other_point.size()}};
  for (const auto& [key, size] : sizes) {
    if (size <= 1) continue;
    if (n > 1 && size != n)
      fail(o.at(key),
           "has " + std::to_string(size) + " values where the others have " + std::to_string(n));
    n = size;
  }
  if (o.has("duration")) {
    const double d = o.positive("duration", 1);
    const double m = std::round(d * ev.rate) + 1;
    if (n > 1 && m != double(n))
      fail(o.at("duration"), "disagrees with the " + std::to_string(n) + " samples at 'rate'");
    if (m > double(kMaxContactSamples)) fail(o.at("duration"), "is too long at this rate");
    n = std::size_t(m);
  }
  if (n < 2)
    fail(o.path(), "a contact needs a 'duration' or per-sample arrays of 2 values or more");
  ev.samples = n;
  if (ev.end_time() > kMaxSceneSeconds) fail(o.path(), "ends past the scene's hour");
  o.done();
  return ev;
}

}  // namespace chladni::scene_parse
