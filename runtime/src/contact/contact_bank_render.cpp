// ContactBank's per-block work: control points in, each contact's input row out.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "chladni/core/error.hpp"
#include "chladni/runtime/contact/contact_bank.hpp"

namespace chladni::runtime {
namespace {

bool valid(float x) {
  return std::isfinite(x) && x >= 0;
}

// Drive per newton of force for one sample: the impulse f / fs kicks q_i by (v_i . n) / omega_d
// per N*s; inline modes carry their pressure per N*s, a model without geometry 1 / omega_d.
std::complex<float> drive(const ObjectModes& o, std::size_t i, std::size_t vertex, double fs) {
  const double wd = o.modes[i].omega_d;
  double per_ns = 0;
  if (o.model && o.model->has_geometry()) {
    const ModalModel& m = *o.model;
    const Vec3 inward = m.normals.empty() ? Vec3{0, 0, -1} : scale(m.normals[vertex], -1.0);
    per_ns = wd > 0 ? dot(m.shape(i, vertex), inward) / wd : 0.0;
  } else if (o.inline_modes) {
    per_ns = (*o.inline_modes)[i].amplitude;
  } else if (wd > 0) {
    per_ns = 1.0 / wd;
  }
  // The stream is the force's second derivative (contact_bank.hpp).
  return {wd > 0 ? static_cast<float>(per_ns / (fs * wd * wd)) : 0.0f, 0.0f};
}

}  // namespace

bool ContactBank::push(int k, const ContactPoint& p) {
  if (!live(k)) return false;
  Contact& c = contacts_[k];
  if (c.size == c.ring.size() || c.end != UINT64_MAX) return false;
  if (c.size > 0 && p.sample < at(c, c.size - 1).sample) return false;
  if (!valid(p.force) || !valid(p.slip) || !valid(p.rolling)) return false;
  for (int b = 0; b < c.body_count; ++b) {
    const std::size_t n = surface_points(c.bodies[b].modes);
    if (n > 0 && p.vertex[b] >= n) return false;
  }
  if (c.size == 0) c.begin = p.sample;  // the first: the ring keeps one from then on
  c.ring[(c.head + c.size) % c.ring.size()] = p;
  ++c.size;
  return true;
}

void ContactBank::end(int k, uint64_t sample) {
  if (!live(k)) return;
  Contact& c = contacts_[k];
  c.end = std::min(c.end, sample);
}

void ContactBank::set_gains(int k, int body, std::span<const float> gains, float left,
                            float right) {
  if (!live(k)) return;
  Contact& c = contacts_[k];
  if (body < 0 || body >= c.body_count || c.fading) return;
  const Body& b = c.bodies[body];
  const uint32_t n = std::min<uint32_t>(b.count, uint32_t(gains.size()));
  for (uint32_t i = 0; i < n; ++i) {
    const float g[2] = {gains[i] * left, gains[i] * right};
    fb_.set_gains(b.first_slot + i, g);
  }
}

uint64_t ContactBank::silent_from() const {
  uint64_t last = 0;
  for (const Contact& c : contacts_) {
    if (!c.live) continue;
    if (c.end == UINT64_MAX) return UINT64_MAX;
    last = std::max(last, c.end + opt_.ramp);
  }
  return last;
}

void ContactBank::drive_gains(Contact& c, uint32_t stream, const ContactPoint& p) {
  for (int b = 0; b < c.body_count; ++b) {
    Body& body = c.bodies[b];
    const int64_t v = surface_points(body.modes) > 0 ? int64_t(p.vertex[b]) : 0;
    if (v == body.vertex) continue;
    body.vertex = v;
    for (uint32_t i = 0; i < body.count; ++i)
      fb_.set_input(body.first_slot + i, stream,
                    drive(body.modes, i, std::size_t(v), opt_.sample_rate));
  }
}

// The per-sample normal force (faded), slip and rolling speed of [now, now + frames).
void ContactBank::fill(Contact& c, uint64_t now, uint32_t frames) {
  const double ramp = std::max<uint32_t>(opt_.ramp, 1);
  std::size_t seg = 0;  // points seg and seg + 1 bracket the sample, where both exist
  for (uint32_t n = 0; n < frames; ++n) {
    const uint64_t t = now + n;
    while (seg + 1 < c.size && at(c, seg + 1).sample <= t) ++seg;
    const ContactPoint& a = at(c, seg);
    float N = a.force, vs = a.slip, vr = a.rolling;
    if (seg + 1 < c.size && t > a.sample) {
      const ContactPoint& b = at(c, seg + 1);
      const float w = float(double(t - a.sample) / double(b.sample - a.sample));
      N += w * (b.force - a.force);
      vs += w * (b.slip - a.slip);
      vr += w * (b.rolling - a.rolling);
    }
    double env = 0;
    if (t >= c.begin) env = std::min(1.0, double(t - c.begin) / ramp);
    if (c.end != UINT64_MAX) env *= std::clamp(1.0 - (double(t) - double(c.end)) / ramp, 0.0, 1.0);
    force_[n] = float(N * env);
    slip_[n] = vs;
    roll_[n] = vr;
  }
}

void ContactBank::render(uint64_t now, uint32_t frames, float* rows) {
  for (uint32_t k = 0; k < count_; ++k) {
    Contact& c = contacts_[k];
    const uint32_t stream = opt_.stream_base + k;
    float* row = rows + std::size_t(stream) * frames;
    if (!c.live || retire(c, k, now)) {
      std::memset(row, 0, sizeof(float) * frames);
      continue;
    }
    // Points wholly behind this block: keep the last one at or before its start.
    while (c.size >= 2 && at(c, 1).sample <= now) {
      c.head = (c.head + 1) % c.ring.size();
      --c.size;
    }
    const bool silent = c.size == 0 || now + frames <= c.begin ||
                        (c.end != UINT64_MAX && now >= c.end + opt_.ramp + 2);
    if (silent) {
      std::memset(row, 0, sizeof(float) * frames);
      std::fill(c.force.begin(), c.force.begin() + frames, 0.0f);
      c.f1 = c.f2 = 0;
      continue;
    }
    drive_gains(c, stream, at(c, 0));
    fill(c, now, frames);
    c.excitation->process(force_.data(), slip_.data(), roll_.data(), frames, c.force.data());
    // f'' by second differences, one sample late (the slots' drive gains hold the 1 / omega_d^2);
    // the lag is the same for every mode.
    const double fs2 = opt_.sample_rate * opt_.sample_rate;
    for (uint32_t n = 0; n < frames; ++n) {
      const float f = c.force[n];
      row[n] = static_cast<float>((double(f) - 2.0 * c.f1 + c.f2) * fs2);
      c.f2 = c.f1;
      c.f1 = f;
    }
  }
}

}  // namespace chladni::runtime
