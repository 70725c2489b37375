#include "chladni/core/modal_model.hpp"
#include <algorithm>

#include <cmath>
#include <limits>
#include <numbers>

#include "chladni/core/error.hpp"

namespace chladni {

double ModalModel::damped_omega(std::size_t i) const {
  return damped_angular_frequency(omega[i], decay[i]);
}

std::size_t ModalModel::nearest_point(const Vec3& p) const {
  std::size_t best = 0;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < points.size(); ++v) {
    const double dx = points[v][0] - p[0], dy = points[v][1] - p[1], dz = points[v][2] - p[2];
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < best_d2) best_d2 = d2, best = v;
  }
  return best;
}

std::pair<Vec3, Vec3> ModalModel::surface_box() const {
  Vec3 lo = points.at(0), hi = points.at(0);
  for (const Vec3& p : points)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], p[c]), hi[c] = std::max(hi[c], p[c]);
  return {lo, hi};
}

void ModalModel::validate() const {
  const std::size_t n = omega.size();
  const std::string who = "modal model '" + name + "'";
  if (decay.size() != n || radiation.size() != n) {
    throw InputError(who + ": " + std::to_string(n) + " frequencies but " +
                     std::to_string(decay.size()) + " decay rates and " +
                     std::to_string(radiation.size()) + " radiation gains");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(omega[i]) || omega[i] <= 0.0 || !std::isfinite(decay[i]) || decay[i] < 0.0 ||
        !std::isfinite(radiation[i])) {
      throw InputError(who + ": mode " + std::to_string(i) +
                       " has a non-finite or out-of-range frequency, decay or radiation gain");
    }
  }
  if (shapes.size() != n * points.size()) {
    throw InputError(who + ": " + std::to_string(shapes.size()) + " shape vectors for " +
                     std::to_string(n) + " modes x " + std::to_string(points.size()) + " points");
  }
  if (transfer) {
    if (transfer->mode_count() != n)
      throw InputError(who + ": transfer has " + std::to_string(transfer->mode_count()) +
                       " modes for " + std::to_string(n));
    transfer->validate();
  }
  if (!normals.empty() && normals.size() != points.size()) {
    throw InputError(who + ": normals and points differ in count");
  }
  for (std::size_t v = 0; v < points.size(); ++v) {
    if (!is_finite(points[v]))
      throw InputError(who + ": point " + std::to_string(v) + " is not finite");
  }
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    if (!is_finite(shapes[k])) {
      throw InputError(who + ": shape of mode " + std::to_string(k / points.size()) + " at point " +
                       std::to_string(k % points.size()) + " is not finite");
    }
  }
}

ModeSelection apply_damping(ModalModel& model, const DampingModel& damping, double min_hz,
                            double max_hz, double sample_rate) {
  damping.validate();
  ModeSelection sel;
  const double top_hz = std::min(max_hz, 0.5 * sample_rate);
  model.decay.resize(model.omega.size());
  for (std::size_t i = 0; i < model.omega.size(); ++i) {
    const double d = 0.5 * damping.coefficient(model.omega[i]);  // d_i = c_i / 2
    model.decay[i] = d;
    if (d >= model.omega[i]) {
      ++sel.overdamped;
      continue;
    }
    const double f = model.damped_omega(i) / (2.0 * std::numbers::pi);
    if (f < min_hz)
      ++sel.below_band;
    else if (f > top_hz)
      ++sel.above_band;
    else
      sel.kept.push_back(i);
  }
  return sel;
}

void keep_modes(ModalModel& model, const std::vector<std::size_t>& kept) {
  ModalModel out;
  out.name = model.name;
  out.points = model.points;
  out.normals = model.normals;
  if (model.transfer) out.transfer = model.transfer->subset(kept);
  for (std::size_t i : kept) {
    out.omega.push_back(model.omega[i]);
    out.decay.push_back(model.decay[i]);
    out.radiation.push_back(model.radiation[i]);
    for (std::size_t v = 0; v < model.points.size(); ++v) out.shapes.push_back(model.shape(i, v));
  }
  model = std::move(out);
}

}  // namespace chladni
