#include "chladni/runtime/filterbank/filterbank.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "chladni/core/error.hpp"

namespace chladni::runtime {

std::complex<float> pole(double omega_d, double decay, double sample_rate) {
  // p = exp((-d + i omega_d) / fs), formed in double before rounding to float.
  const double r = std::exp(-decay / sample_rate);
  const double a = omega_d / sample_rate;
  return {static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a))};
}

SlotLease Filterbank::lease(uint32_t count) {
  if (leases_ >= kMaxLeases)
    throw InputError("the filterbank is shared by " + std::to_string(kMaxLeases) +
                     " users already");
  if (count > unleased())
    throw InputError("the filterbank has " + std::to_string(unleased()) + " free slots; " +
                     std::to_string(count) + " were asked for");
  SlotLease l{leased_end_, leased_end_ + count, leases_++};
  begin_[l.id] = l.begin;
  released_[l.id] = false;
  used_end_[l.id] = 0;
  leased_end_ = l.end;
  return l;
}

void Filterbank::release(const SlotLease& lease) {
  if (lease.id < 0 || lease.id >= leases_ || released_[lease.id]) return;
  released_[lease.id] = true;
  used_end_[lease.id] = 0;
  while (leases_ > 0 && released_[leases_ - 1]) leased_end_ = begin_[--leases_];
}

void Filterbank::set_used(const SlotLease& lease, uint32_t used) {
  if (lease.id < 0 || lease.id >= leases_) return;
  used_end_[lease.id] = used ? lease.begin + std::min(used, lease.size()) : 0;
  uint32_t high = 0;
  for (int i = 0; i < leases_; ++i) high = std::max(high, used_end_[i]);
  set_high_water(high);
}

}  // namespace chladni::runtime
