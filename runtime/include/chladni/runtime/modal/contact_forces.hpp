#pragma once
// The sound of an impact while its contact lasts. The filterbank receives, at the first sample
// after the contact starts, the state that is exact once the contact is over (contact_weight.hpp's
// W, advanced to that sample). During the contact that state is wrong: it jumps in at once, where
// the true response builds up from zero under the half-sine force F(s) = (J pi / 2 tau)
// sin(pi s / tau). ContactForces adds the difference, per mode
//   d[n] = z_true(t_n) - W exp(lambda (t_n - t0)),
// which obeys the mode's own recurrence with the force as input,
//   d[n] = p d[n-1] + a * integral_{t_{n-1}}^{t_n} F(s - t0) exp(lambda (t_n - s)) ds,
// and reaches zero exactly when the contact ends. The integral over each sample interval is a
// 4-point Gauss-Legendre rule (the integrand turns by at most half a period per sample), all in
// double precision, so the output equals the continuous solution sampled, with no step at the
// contact's start and none at its end.
//
// Storage is fixed at construction; begin() and render() do not allocate.
#include <complex>
#include <cstdint>
#include <vector>

namespace chladni::runtime {

class ContactForces {
 public:
  /// Mode gains per output channel, read once per render for each driven mode.
  using GainFn = void (*)(const void* context, int32_t voice, uint32_t mode, float gains[2]);

  ContactForces(double sample_rate, uint32_t max_modes, uint32_t max_contacts);

  /// Starts a contact at fractional sample `t0` (absolute) lasting `tau` seconds, one that
  /// reaches past its first sample (end_sample() > ceil(t0): otherwise the kick alone is exact
  /// and there is nothing to drive). Modes are added with add_mode() until the next begin() or
  /// render(). False when no contact is free.
  bool begin(int32_t voice, double t0, double tau);
  /// Adds one mode to the contact being begun: decay rate and damped angular frequency, the
  /// state kick `a` of the whole impulse, and `kick`, the state the filterbank receives at
  /// `first_sample` (= ceil(t0)). False when the mode storage is full (the mode then sounds as
  /// the filterbank has it).
  bool add_mode(uint32_t mode, double omega_d, double decay, std::complex<double> a,
                std::complex<double> kick);
  /// Adds the contacts' corrections for absolute samples [now, now + frames) to `out`
  /// (interleaved, `channels` of 1 or 2), and forgets contacts that are over.
  void render(uint64_t now, uint32_t frames, int channels, float* out, GainFn gain,
              const void* context);
  /// Forgets the contacts of a voice (stopped).
  void drop_voice(int32_t voice);

  /// First sample after the contact ends: from it on, the filterbank alone is exact.
  static int64_t end_sample(double t0, double tau, double sample_rate);
  uint32_t active_contacts() const { return static_cast<uint32_t>(contacts_.size()); }

 private:
  struct Mode {
    uint32_t mode;
    std::complex<double> d, p, a;
    std::complex<double> e[4];  // w_k exp(lambda T (1 - x_k)): one full interval's rule
    float g[2];                 // channel gains, read at each render
  };
  struct Contact {
    int32_t voice;
    double t0, tau;  // samples
    int64_t next;    // sample whose d is stored in the modes (the next to emit)
    int64_t end;     // first sample past the contact
    uint32_t first, count;
  };
  void compact();

  double fs_;
  std::vector<Mode> modes_;        // capacity fixed; contacts own contiguous ranges
  std::vector<Contact> contacts_;  // capacity fixed
  uint32_t used_ = 0;              // modes_ entries in use at the end (after compaction)
};

}  // namespace chladni::runtime
