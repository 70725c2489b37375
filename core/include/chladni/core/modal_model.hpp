#pragma once
// The modal description of one object (DESIGN.md "Modal model"): per mode its undamped angular
// frequency, decay rate and radiation gain, and, when the object has geometry, its mass-normalized
// shape at surface sample points so that impacts can be placed.
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "chladni/core/damping.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/core/vec3.hpp"

namespace chladni {

/// Damped angular frequency sqrt(omega^2 - d^2) of a mode (0 when overdamped).
inline double damped_angular_frequency(double omega, double decay) {
  const double w2 = omega * omega - decay * decay;
  return w2 > 0.0 ? std::sqrt(w2) : 0.0;
}

struct ModalModel {
  std::string name;
  std::vector<double> omega;  ///< undamped angular frequency omega_i (rad/s)
  std::vector<double> decay;  ///< decay rate d_i = c_i / 2 (1/s)
  /// Pressure at 1 m per unit modal acceleration: a compact-source estimate, used without transfer.
  std::vector<double> radiation;
  /// Surface sample points (m, object frame) and mode shapes there:
  /// shape(i, v) = shapes[(i * points.size() + v)], one 3-vector per mode and point.
  std::vector<Vec3> points;
  std::vector<Vec3> normals;  ///< outward unit normal per point (may be empty)
  std::vector<Vec3> shapes;
  /// Far-field multipole expansion per mode (soundbanks precomputed with transfer); when present
  /// the listener gain of mode i is |p_i(listener)| instead of radiation_i omega_d^2 / r.
  std::optional<Transfer> transfer;

  std::size_t mode_count() const { return omega.size(); }
  bool has_geometry() const { return !points.empty(); }
  const Vec3& shape(std::size_t mode, std::size_t point) const {
    return shapes[mode * points.size() + point];
  }
  /// Damped angular frequency omega_d = sqrt(omega^2 - d^2) (0 when overdamped).
  double damped_omega(std::size_t mode) const;
  /// Index of the surface point nearest to p. Requires geometry.
  std::size_t nearest_point(const Vec3& p) const;
  /// The axis-aligned box of the surface points (lo, hi). Requires geometry.
  std::pair<Vec3, Vec3> surface_box() const;
  /// Throws InputError naming the first inconsistent count or non-finite value.
  void validate() const;
};

/// Which modes survive damping and band limits, and why others were dropped.
struct ModeSelection {
  std::vector<std::size_t> kept;
  std::size_t overdamped = 0;  ///< d >= omega
  std::size_t below_band = 0;  ///< damped frequency below min_hz
  std::size_t above_band = 0;  ///< damped frequency above max_hz or Nyquist
};

/// Applies a damping model to undamped frequencies: fills decay (d = c/2) and reports which modes
/// lie in [min_hz, min(max_hz, sample_rate/2)] and are underdamped (DESIGN.md conventions).
ModeSelection apply_damping(ModalModel& model, const DampingModel& damping, double min_hz,
                            double max_hz, double sample_rate);

/// Keeps only the listed modes (in that order).
void keep_modes(ModalModel& model, const std::vector<std::size_t>& kept);

}  // namespace chladni
