#include "chladni/runtime/contact/contact_excitation.hpp"

namespace chladni::runtime {

ContactExcitation::ContactExcitation(const SurfaceProfile& profile, double sample_rate,
                                     double start)
    : profile_(&profile), fs_(sample_rate), s_slide_(start), s_roll_(start) {}

void ContactExcitation::process(const float* force, const float* slip, const float* rolling,
                                uint32_t frames, float* out) {
  const Roughness& r = profile_->roughness();
  const double nyquist = 0.5 * fs_, dt = 1.0 / fs_;
  const double roll_scale = r.height / kStandardGravity;
  for (uint32_t n = 0; n < frames; ++n) {
    const double N = force[n], vs = slip[n], vr = rolling[n];
    double f = 0;
    if (vs != 0) {
      const double gate = vs * vs / (vs * vs + kSlipGate * kSlipGate);
      f += r.level * N * gate * profile_->height(s_slide_, vs, nyquist);
    }
    if (vr != 0) f += N * roll_scale * vr * vr * profile_->curvature(s_roll_, vr, nyquist);
    out[n] = static_cast<float>(f);
    s_slide_ += vs * dt;
    s_roll_ += vr * dt;
  }
}

}  // namespace chladni::runtime
