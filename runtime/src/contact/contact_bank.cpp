#include "chladni/runtime/contact/contact_bank.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "chladni/core/error.hpp"

namespace chladni::runtime {
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
  contacts_.resize(o.max_contacts);
  retired_.reserve(o.max_contacts);
  // Each live contact splits at most one run in two.
  free_runs_.reserve(std::size_t{o.max_contacts} + 2);
  free_runs_.give(lease_.begin, lease_.size());
  force_.assign(fb.max_frames(), 0.0f);
  slip_.assign(fb.max_frames(), 0.0f);
  roll_.assign(fb.max_frames(), 0.0f);
}

ContactBank::~ContactBank() {
  for (uint32_t s = lease_.begin; s < lease_.begin + slot_end_; ++s) fb_.clear_mode(s);
  fb_.set_used(lease_, 0);
  fb_.release(lease_);
}

std::unique_ptr<ContactBank::Prepared> ContactBank::prepare(const ContactSpec& spec) const {
  const std::string who = spec.name.empty() ? std::string("contact") : spec.name;
  auto p = std::make_unique<Prepared>();
  Contact& c = p->contact;
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
  double slowest = 1e9;
  for (int b = 0; b < c.body_count; ++b) {
    const ObjectModes* o = spec.bodies[b];
    if (!o || o->modes.empty()) throw InputError(who + ": a body in contact has no modes");
    c.bodies[b].modes = *o;
    c.bodies[b].count = uint32_t(o->modes.size());
    c.slots += c.bodies[b].count;
    for (const ModeSpec& m : o->modes) slowest = std::min(slowest, std::max(m.decay, 1e-3));
  }
  if (c.slots > lease_.size())
    throw InputError(who + ": needs " + std::to_string(c.slots) +
                     " filterbank slots, the bank has " + std::to_string(lease_.size()));
  c.ring_down = uint64_t(std::ceil(std::log(1e3) / slowest * opt_.sample_rate));
  c.ring.resize(opt_.max_points);
  c.force.assign(fb_.max_frames(), 0.0f);
  return p;
}

bool ContactBank::install(Prepared& p, uint32_t index) noexcept {
  if (index >= contacts_.size() || contacts_[index].live || p.contact.slots == 0) return false;
  const uint32_t first = free_runs_.take(p.contact.slots);
  if (first == ~0u) return false;
  std::swap(contacts_[index], p.contact);
  Contact& c = contacts_[index];
  c.live = true;
  c.first_slot = first;
  const uint32_t stream = opt_.stream_base + index;
  const float silent[2] = {0, 0};
  uint32_t slot = first;
  for (int b = 0; b < c.body_count; ++b) {
    Body& body = c.bodies[b];
    body.first_slot = slot;
    body.vertex = -1;
    for (uint32_t i = 0; i < body.count; ++i, ++slot) {
      const ModeSpec& m = body.modes.modes[i];
      fb_.set_mode(slot, pole(m.omega_d, m.decay, opt_.sample_rate), silent);
      fb_.set_input(slot, stream, {0, 0});
    }
  }
  count_ = std::max(count_, index + 1);
  slot_end_ = std::max(slot_end_, first + c.slots - lease_.begin);
  fb_.set_used(lease_, slot_end_);
  return true;
}

int ContactBank::add_contact(const ContactSpec& spec) {
  std::unique_ptr<Prepared> p = prepare(spec);
  if (!install(*p, count_))
    throw InputError(p->contact.name + ": the bank has no room (" +
                     std::to_string(opt_.max_contacts) + " contacts, " +
                     std::to_string(lease_.size()) + " slots)");
  return int(count_ - 1);
}

void ContactBank::remove(int k, uint64_t sample) {
  if (!live(k)) return;
  Contact& c = contacts_[k];
  end(k, sample);
  c.retire_at = std::min(c.retire_at, c.end + opt_.ramp + 2 + c.ring_down);
}

// Its modes rung down: the gains ramp to zero, then the slots are cleared and given back. True
// when the contact is gone.
bool ContactBank::retire(Contact& c, uint32_t index, uint64_t now) {
  if (c.retire_at == UINT64_MAX || now < c.retire_at) return false;
  if (!c.fading) {
    const float zero[2] = {0, 0};
    for (uint32_t s = c.first_slot; s < c.first_slot + c.slots; ++s) fb_.set_gains(s, zero);
    c.fading = true;
    c.free_at = now + fb_.gain_ramp();
    return false;
  }
  if (now < c.free_at) return false;
  for (uint32_t s = c.first_slot; s < c.first_slot + c.slots; ++s) fb_.clear_mode(s);
  free_runs_.give(c.first_slot, c.slots);
  c.live = c.fading = false;
  c.retire_at = UINT64_MAX;
  if (retired_.size() < retired_.capacity()) retired_.push_back(index);
  return true;
}

}  // namespace chladni::runtime
