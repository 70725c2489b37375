#include "chladni/estimate/struck_modes.hpp"

#include <cmath>

#include "chladni/core/error.hpp"
#include "chladni/runtime/modal/object_modes.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"

namespace chladni::estimate {

StruckModes struck_modes(const ModalModel& model, std::size_t point, const Vec3& listener,
                         double gamma) {
  if (!model.has_geometry() || model.normals.size() != model.points.size())
    throw InputError("the object has no surface points with normals to strike");
  if (point >= model.points.size())
    throw InputError("hit vertex " + std::to_string(point) + " is out of range (the object has " +
                     std::to_string(model.points.size()) + " surface points)");
  runtime::ObjectModes object = runtime::object_modes(model);
  runtime::gains_at_listener(model, object, listener);
  StruckModes out;
  out.gamma = gamma;
  const Vec3& n = model.normals[point];
  for (std::size_t i = 0; i < model.mode_count(); ++i) {
    const double w = model.omega[i];
    if (!(w > 0)) continue;
    out.omega.push_back(w);
    out.amplitude.push_back(
        std::abs(double(object.modes[i].gain) * dot(model.shape(i, point), n) / w));
  }
  return out;
}

}  // namespace chladni::estimate
