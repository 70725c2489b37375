#include "chladni/report/radiation.hpp"

#include <algorithm>
#include <cmath>

#include "chladni/runtime/modal/object_modes.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"

namespace chladni::report {

std::vector<std::vector<double>> gains_towards(const ModalModel& model, const Vec3& centre,
                                               double distance,
                                               const std::vector<Vec3>& directions) {
  // gains_at_listener sets each mode's gain once, from the model's own: a fresh copy each time.
  const runtime::ObjectModes base = runtime::object_modes(model);
  std::vector<std::vector<double>> out;
  out.reserve(directions.size());
  for (const Vec3& d : directions) {
    runtime::ObjectModes object = base;
    runtime::gains_at_listener(model, object, add(centre, scale(d, distance)));
    std::vector<double>& g = out.emplace_back(object.modes.size());
    for (std::size_t i = 0; i < g.size(); ++i) g[i] = std::abs(double(object.modes[i].gain));
  }
  return out;
}

std::vector<double> radiation_at_1m(const ModalModel& model) {
  const Vec3 c = model.transfer ? model.transfer->centre : Vec3{0, 0, 0};
  const double r = std::max(1.0, model.transfer ? 4 * model.transfer->radius : 1.0);
  std::vector<Vec3> dirs{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int k = 0; k < 8; ++k)
    dirs.push_back(scale(Vec3{k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, k & 4 ? 1.0 : -1.0},
                         1 / std::sqrt(3.0)));
  std::vector<double> sum(model.mode_count(), 0.0);
  for (const std::vector<double>& g : gains_towards(model, c, r, dirs))
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += g[i] * g[i];
  std::vector<double> out(sum.size());
  for (std::size_t i = 0; i < sum.size(); ++i) {
    const double wd = model.damped_omega(i);
    out[i] = wd > 0 ? std::sqrt(sum[i] / double(dirs.size())) * r / (wd * wd) : NAN;
  }
  return out;
}

}  // namespace chladni::report
