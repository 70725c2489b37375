#include "chladni/runtime/modal/contact_forces.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace chladni::runtime {
namespace {

// Gauss-Legendre on [0, 1], 4 points: exact to degree 7.
constexpr double kX[4] = {0.5 - 0.4305681557970263, 0.5 - 0.1699905217924281,
                          0.5 + 0.1699905217924281, 0.5 + 0.4305681557970263};
constexpr double kW[4] = {0.1739274225687269, 0.3260725774312731, 0.3260725774312731,
                          0.1739274225687269};

// The force per unit impulse at sample time u, for a contact [t0, t0 + tau] (samples): its
// integral over u is 1.
double force(double u, double t0, double tau) {
  if (u <= t0 || u >= t0 + tau) return 0.0;
  return std::numbers::pi / (2.0 * tau) * std::sin(std::numbers::pi * (u - t0) / tau);
}

}  // namespace

ContactForces::ContactForces(double sample_rate, uint32_t max_modes, uint32_t max_contacts)
    : fs_(sample_rate) {
  modes_.resize(max_modes);
  contacts_.reserve(max_contacts);
}

int64_t ContactForces::end_sample(double t0, double tau, double sample_rate) {
  return static_cast<int64_t>(std::ceil(t0 + tau * sample_rate));
}

bool ContactForces::begin(int32_t voice, double t0, double tau) {
  if (contacts_.size() == contacts_.capacity()) return false;
  contacts_.push_back({voice, t0, tau * fs_, static_cast<int64_t>(std::ceil(t0)),
                       end_sample(t0, tau, fs_), used_, 0});
  return true;
}

bool ContactForces::add_mode(uint32_t mode, double omega_d, double decay, std::complex<double> a,
                             std::complex<double> kick) {
  if (contacts_.empty()) return false;
  Contact& c = contacts_.back();
  if (c.first + c.count != used_) return false;  // not the contact being begun
  if (used_ == modes_.size()) {
    compact();
    if (used_ == modes_.size()) return false;
  }
  const std::complex<double> ls(-decay / fs_, omega_d / fs_);  // lambda per sample
  Mode& m = modes_[used_++];
  ++contacts_.back().count;
  m.mode = mode;
  m.p = std::exp(ls);
  m.a = a;
  for (int k = 0; k < 4; ++k) m.e[k] = kW[k] * std::exp(ls * (1.0 - kX[k]));
  // The first interval, [t0, first sample], is partial: its own rule.
  const Contact& cc = contacts_.back();
  const double len = static_cast<double>(cc.next) - cc.t0;
  std::complex<double> z = 0.0;
  for (int k = 0; k < 4 && len > 0; ++k) {
    z += kW[k] * force(cc.t0 + kX[k] * len, cc.t0, cc.tau) * std::exp(ls * len * (1.0 - kX[k]));
  }
  m.d = a * len * z - kick;
  return true;
}

void ContactForces::compact() {
  uint32_t w = 0;
  for (Contact& c : contacts_) {
    if (c.first != w)
      std::copy(modes_.begin() + c.first, modes_.begin() + c.first + c.count, modes_.begin() + w);
    c.first = w;
    w += c.count;
  }
  used_ = w;
}

void ContactForces::render(uint64_t now, uint32_t frames, int channels, float* out, GainFn gain,
                           const void* context) {
  const int64_t t_begin = static_cast<int64_t>(now);
  const int64_t t_end = t_begin + frames;
  for (Contact& c : contacts_) {
    Mode* m = modes_.data() + c.first;
    for (uint32_t i = 0; i < c.count; ++i) gain(context, c.voice, m[i].mode, m[i].g);
    for (int64_t n = c.next; n < c.end && n < t_end; ++n) {
      // The force at the nodes of the next interval, [n, n + 1], shared by the contact's modes.
      double f[4];
      for (int k = 0; k < 4; ++k) f[k] = force(static_cast<double>(n) + kX[k], c.t0, c.tau);
      double left = 0, right = 0;
      for (uint32_t i = 0; i < c.count; ++i) {
        const double im = m[i].d.imag();
        left += m[i].g[0] * im;
        right += m[i].g[1] * im;
        const std::complex<double> drive =
            f[0] * m[i].e[0] + f[1] * m[i].e[1] + f[2] * m[i].e[2] + f[3] * m[i].e[3];
        m[i].d = m[i].p * m[i].d + m[i].a * drive;
      }
      if (n >= t_begin) {
        float* o = out + (n - t_begin) * channels;
        o[0] += static_cast<float>(left);
        if (channels == 2) o[1] += static_cast<float>(right);
      }
      c.next = n + 1;
    }
  }
  // Forget the contacts that are over (erase keeps capacity: no allocation).
  std::erase_if(contacts_, [&](const Contact& c) { return c.next >= c.end || c.count == 0; });
  if (contacts_.empty()) used_ = 0;
}

void ContactForces::drop_voice(int32_t voice) {
  std::erase_if(contacts_, [&](const Contact& c) { return c.voice == voice; });
  if (contacts_.empty()) used_ = 0;
}

}  // namespace chladni::runtime
