#pragma once
// The force a continuous contact puts into an object, sample by sample, from its normal force
// N, slip speed v_s and rolling speed v_r:
//   f = level * N * g(v_s) * y(s_s)  +  (N / g0) * height * v_r^2 * y_c''(s_r),
//   g(v) = v^2 / (v^2 + v0^2),   s_s' = v_s,   s_r' = v_r.
// Sliding (FoleyAutomatic's phonograph needle): the friction force fluctuates by `level` of the
// normal force as the contact reads the unit-rms profile y at its slip position; the gate g
// (v0 = 1 mm/s) takes it to exactly zero when the slip stops, where a needle reading a frozen
// profile would hold a static force. Rolling (FoleyAutomatic's rolling model): the rolling body,
// of mass N / g0, follows the patch-smoothed profile y_c, and the force is its inertia, m times
// d^2 y_c / dt^2 = v_r^2 y_c'' (the term dv_r/dt y_c' is dropped: it is smaller by the ratio of
// the acceleration's time scale to the period of what is heard).
// What follows, for a profile P(k) = C k^-beta read at v (surface_profile.hpp): the force's
// one-sided spectrum is S(f) = level^2 N^2 C (f/v)^-beta / v for sliding, so a mode at f rings
// with power proportional to N^2 v^(beta - 1), and the band, hence the spectral centroid, moves
// up in proportion to v; rolling gives (N h / g0)^2 (2 pi f)^4 C (f/v)^-beta H(f/v)^2 / v.
#include <cstdint>

#include "chladni/runtime/contact/surface_profile.hpp"

namespace chladni::runtime {

/// Standard gravity: the rolling body's mass is its normal force over it.
constexpr double kStandardGravity = 9.80665;
/// Slip speed (m/s) below which the sliding force fades out.
constexpr double kSlipGate = 1e-3;

class ContactExcitation {
 public:
  /// `profile` must outlive this; `start` offsets both read positions (m), so that contacts on
  /// the same surface do not sound alike.
  ContactExcitation(const SurfaceProfile& profile, double sample_rate, double start = 0);

  /// Writes `frames` samples of force (N) from per-sample normal force (N), slip and rolling
  /// speeds (m/s). Allocates nothing.
  void process(const float* force, const float* slip, const float* rolling, uint32_t frames,
               float* out);

  double slide_position() const { return s_slide_; }
  double roll_position() const { return s_roll_; }

 private:
  const SurfaceProfile* profile_;
  double fs_;
  double s_slide_, s_roll_;
};

}  // namespace chladni::runtime
