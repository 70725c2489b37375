#include "chladni/runtime/modal/object_modes.hpp"

#include <numbers>
#include <string>

#include "chladni/core/error.hpp"

namespace chladni::runtime {

ObjectModes object_modes(const ModalModel& model) {
  model.validate();
  ObjectModes o;
  o.model = &model;
  if (model.transfer) o.transfer = &*model.transfer;
  for (std::size_t i = 0; i < model.mode_count(); ++i) {
    const double wd = model.damped_omega(i);
    o.modes.push_back({wd, model.decay[i], static_cast<float>(model.radiation[i] * wd * wd)});
  }
  return o;
}

ObjectModes object_modes(const std::vector<InlineMode>& modes) {
  ObjectModes o;
  o.inline_modes = &modes;
  for (const InlineMode& m : modes)
    o.modes.push_back({2.0 * std::numbers::pi * m.frequency, m.decay, 1.0f});
  return o;
}

void impact_coupling(const ObjectModes& object, const ImpactEvent& ev,
                     std::vector<std::complex<float>>& out) {
  out.resize(object.modes.size());
  std::size_t point = 0;
  if (object.model && object.model->has_geometry()) {
    if (ev.vertex) {
      if (*ev.vertex >= object.model->points.size()) {
        throw InputError(ev.json_path + ".vertex: " + std::to_string(*ev.vertex) +
                         " is out of range (object has " +
                         std::to_string(object.model->points.size()) + " surface points)");
      }
      point = *ev.vertex;
    } else if (ev.point) {
      point = object.model->nearest_point(*ev.point);
    }
  }
  for (std::size_t i = 0; i < object.modes.size(); ++i) {
    const ModeSpec& m = object.modes[i];
    double w = ev.impulse;
    if (object.inline_modes) {
      w *= (*object.inline_modes)[i].amplitude;
    } else if (object.model) {
      // q_i = (v_i(x) . n) J / omega_d ... (DESIGN.md)
      const double vn =
          object.model->has_geometry() ? dot(object.model->shape(i, point), ev.direction) : 1.0;
      w *= m.omega_d > 0 ? vn / m.omega_d : 0.0;
    }
    out[i] = std::complex<float>(static_cast<float>(w), 0.0f);
  }
}

}  // namespace chladni::runtime
