#include "chladni/runtime/contact/contact_bank.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "chladni/core/error.hpp"

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

std::size_t points(const ObjectModes& o) {
  return o.model && o.model->has_geometry() ? o.model->points.size() : 0;
}

}  // namespace

ContactBank::ContactBank(Filterbank& fb, const ContactBankOptions& o) : fb_(fb), opt_(o) {
  if (!(std::isfinite(o.sample_rate) && o.sample_rate > 0))
    throw InputError("sample rate must be finite and > 0");
  if (o.max_contacts == 0 || o.max_points < 2)
    throw InputError("a contact bank needs max_contacts > 0 and max_points >= 2");
  if (o.stream_base + o.max_contacts > fb.max_streams())
    throw InputError("the filterbank takes " + std::to_string(fb.max_streams()) +
                     " input streams; contacts need " +
                     std::to_string(o.stream_base + o.max_contacts));
  lease_ = fb.lease(o.slots ? o.slots : fb.unleased());
  contacts_.reserve(o.max_contacts);
  force_.assign(fb.max_frames(), 0.0f);
  slip_.assign(fb.max_frames(), 0.0f);
  roll_.assign(fb.max_frames(), 0.0f);
}

ContactBank::~ContactBank() {
  for (uint32_t s = lease_.begin; s < lease_.begin + used_; ++s) fb_.clear_mode(s);
  fb_.set_used(lease_, 0);
  fb_.release(lease_);
}

int ContactBank::add_contact(const ContactSpec& spec) {
  const std::string who = spec.name.empty() ? std::string("contact") : spec.name;
  if (contacts_.size() >= opt_.max_contacts)
    throw InputError(who + ": the bank holds " + std::to_string(opt_.max_contacts) + " contacts");
  Contact c;
  c.name = who;
  try {
    c.profile = std::make_unique<SurfaceProfile>(spec.roughness, spec.seed);
  } catch (const InputError& e) {
    throw InputError(who + ": " + e.what());
  }
  // Contacts on one surface start at different places along it.
  const double start =
      c.profile->length() * double((spec.seed * 0x9e3779b97f4a7c15ull) >> 11) * 0x1.0p-53;
  c.excitation = std::make_unique<ContactExcitation>(*c.profile, opt_.sample_rate, start);
  c.body_count = spec.bodies[1] ? 2 : 1;
  const uint32_t stream = opt_.stream_base + uint32_t(contacts_.size());
  uint32_t need = 0;
  for (int b = 0; b < c.body_count; ++b) {
    const ObjectModes* o = spec.bodies[b];
    if (!o || o->modes.empty()) throw InputError(who + ": a body in contact has no modes");
    need += uint32_t(o->modes.size());
  }
  if (need > lease_.size() - used_)
    throw InputError(who + ": needs " + std::to_string(need) + " filterbank slots, " +
                     std::to_string(lease_.size() - used_) + " are free");
  for (int b = 0; b < c.body_count; ++b) {
    Body& body = c.bodies[b];
    body.modes = *spec.bodies[b];
    body.first_slot = lease_.begin + used_;
    body.count = uint32_t(body.modes.modes.size());
    const float silent[2] = {0, 0};
    for (uint32_t i = 0; i < body.count; ++i) {
      const ModeSpec& m = body.modes.modes[i];
      fb_.set_mode(body.first_slot + i, pole(m.omega_d, m.decay, opt_.sample_rate), silent);
      fb_.set_input(body.first_slot + i, stream, {0, 0});
    }
    used_ += body.count;
  }
  c.ring.resize(opt_.max_points);
  c.force.assign(fb_.max_frames(), 0.0f);
  contacts_.push_back(std::move(c));
  fb_.set_used(lease_, used_);
  return int(contacts_.size() - 1);
}

bool ContactBank::push(int k, const ContactPoint& p) {
  if (k < 0 || std::size_t(k) >= contacts_.size()) return false;
  Contact& c = contacts_[k];
  if (c.size == c.ring.size() || c.end != UINT64_MAX) return false;
  if (c.size > 0 && p.sample < at(c, c.size - 1).sample) return false;
  if (!valid(p.force) || !valid(p.slip) || !valid(p.rolling)) return false;
  for (int b = 0; b < c.body_count; ++b) {
    const std::size_t n = points(c.bodies[b].modes);
    if (n > 0 && p.vertex[b] >= n) return false;
  }
  if (!c.started && c.size == 0) c.begin = p.sample;
  c.ring[(c.head + c.size) % c.ring.size()] = p;
  ++c.size;
  return true;
}

void ContactBank::end(int k, uint64_t sample) {
  if (k < 0 || std::size_t(k) >= contacts_.size()) return;
  Contact& c = contacts_[k];
  c.end = std::min(c.end, sample);
}

void ContactBank::set_gains(int k, int body, std::span<const float> gains, float left,
                            float right) {
  if (k < 0 || std::size_t(k) >= contacts_.size()) return;
  Contact& c = contacts_[k];
  if (body < 0 || body >= c.body_count) return;
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
    if (c.end == UINT64_MAX) return UINT64_MAX;
    last = std::max(last, c.end + opt_.ramp);
  }
  return last;
}

void ContactBank::drive_gains(Contact& c, uint32_t stream, const ContactPoint& p) {
  for (int b = 0; b < c.body_count; ++b) {
    Body& body = c.bodies[b];
    const int64_t v = points(body.modes) > 0 ? int64_t(p.vertex[b]) : 0;
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

void ContactBank::prepare(uint64_t now, uint32_t frames, float* rows) {
  for (std::size_t k = 0; k < contacts_.size(); ++k) {
    Contact& c = contacts_[k];
    const uint32_t stream = opt_.stream_base + uint32_t(k);
    float* row = rows + std::size_t(stream) * frames;
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
    c.started = true;
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
