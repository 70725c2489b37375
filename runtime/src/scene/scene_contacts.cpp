#include "chladni/runtime/scene/scene_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "chladni/core/error.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"

namespace chladni::runtime {
namespace {

// A contact point may lie this far off the surface, as a share of the object's bounding-box
// diagonal: the surface samples are the mesh's vertices, and a point on a large face lies up to
// half its edge from them.
constexpr double kOffSurface = 0.1;

double diagonal(const ModalModel& m) {
  const auto [lo, hi] = m.surface_box();
  const Vec3 d = sub(hi, lo);
  return std::sqrt(dot(d, d));
}

// Each sample's nearest surface point of a body, checked to lie near the surface.
std::vector<uint32_t> vertices(const ContactEvent& ev, const ObjectModes& o,
                               const std::vector<Vec3>& pts, const std::string& key) {
  std::vector<uint32_t> out(ev.samples, 0);
  if (!o.model || !o.model->has_geometry() || pts.empty()) return out;
  const ModalModel& m = *o.model;
  const double limit = kOffSurface * diagonal(m);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::size_t v = m.nearest_point(pts[i]);
    const Vec3 d = sub(m.points[v], pts[i]);
    const double off = std::sqrt(dot(d, d));
    if (off > limit) {
      const std::string at = pts.size() == 1 ? key : key + "[" + std::to_string(i) + "]";
      throw InputError(ev.json_path + "." + at + ": lies " + std::to_string(off) +
                       " m off the surface of '" + m.name + "' (at most " + std::to_string(limit) +
                       " m, a tenth of its size)");
    }
    if (pts.size() == 1) {
      std::fill(out.begin(), out.end(), uint32_t(v));
      break;
    }
    out[i] = uint32_t(v);
  }
  return out;
}

float value(const std::vector<double>& v, std::size_t i) {
  return static_cast<float>(v.size() == 1 ? v[0] : v[i]);
}

}  // namespace

Roughness resolve_roughness(const RoughnessSpec& s) {
  Roughness r = roughness_preset(s.surface);
  if (s.level) r.level = *s.level;
  if (s.height) r.height = *s.height;
  if (s.beta) r.beta = *s.beta;
  if (s.shortest) r.shortest = *s.shortest;
  if (s.longest) r.longest = *s.longest;
  if (s.patch) r.patch = *s.patch;
  if (s.ribs) r.ribs = *s.ribs;
  if (s.rib_depth) r.rib_depth = *s.rib_depth;
  validate_roughness(r);
  return r;
}

std::vector<SceneContact> scene_contacts(const Scene& scene,
                                         const std::vector<ObjectModes>& objects) {
  std::vector<SceneContact> out;
  const double fs = scene.sample_rate;
  for (const ContactEvent& ev : scene.contacts) {
    SceneContact c;
    try {
      c.roughness = resolve_roughness(ev.roughness);
    } catch (const InputError& e) {
      throw InputError(ev.json_path + ".roughness: " + e.what());
    }
    const std::vector<uint32_t> v0 = vertices(ev, objects.at(ev.object), ev.point, "point");
    const std::vector<uint32_t> v1 =
        ev.other ? vertices(ev, objects.at(*ev.other), ev.other_point, "other_point")
                 : std::vector<uint32_t>(ev.samples, 0);
    c.points.resize(ev.samples);
    for (std::size_t i = 0; i < ev.samples; ++i) {
      ContactPoint& p = c.points[i];
      p.sample = static_cast<uint64_t>(std::llround((ev.time + double(i) / ev.rate) * fs));
      p.force = value(ev.force, i);
      p.slip = value(ev.slip, i);
      p.rolling = value(ev.rolling, i);
      p.vertex = {v0[i], v1[i]};
    }
    out.push_back(std::move(c));
  }
  return out;
}

uint32_t contact_slots(const Scene& scene, const std::vector<ObjectModes>& objects) {
  std::size_t slots = 0;
  for (const ContactEvent& ev : scene.contacts) {
    slots += objects.at(ev.object).modes.size();
    if (ev.other) slots += objects.at(*ev.other).modes.size();
  }
  return static_cast<uint32_t>(std::min<std::size_t>(slots, std::numeric_limits<uint32_t>::max()));
}

uint32_t contact_points_per_block(const Scene& scene, uint32_t frames) {
  double rate = 0;
  for (const ContactEvent& ev : scene.contacts) rate = std::max(rate, ev.rate);
  return std::max<uint32_t>(64, uint32_t(std::ceil(rate * frames / scene.sample_rate)) + 3);
}

}  // namespace chladni::runtime
