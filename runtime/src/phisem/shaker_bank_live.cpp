// The shaker bank's voices coming and going while it plays: validated and built off the audio
// thread, placed and removed on it without allocating, their slots taken from runs that removed
// voices gave back.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "shaker_gpu_stage.hpp"

namespace chladni::runtime {
namespace {

bool finite(std::complex<float> c) {
  return std::isfinite(c.real()) && std::isfinite(c.imag());
}

void check_voice(const ShakerVoice& sv) {
  const std::size_t n = sv.resonances.size();
  if (n == 0) throw InputError("voice '" + sv.name + "' has no resonances");
  const PhisemParams& p = sv.excitation;
  for (float x : {p.system_decay, p.sound_decay, p.collision_probability, p.gain, p.eq[0], p.eq[1],
                  p.eq[2], sv.pan[0], sv.pan[1]}) {
    if (!std::isfinite(x)) throw InputError("voice '" + sv.name + "': non-finite parameter");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const ShakerResonance& r = sv.resonances[i];
    if (!(std::isfinite(r.omega_d) && std::isfinite(r.decay) && r.decay >= 0 && finite(r.input) &&
          std::isfinite(r.gain) && std::isfinite(r.vary) && std::isfinite(r.sweep) && r.sweep > 0))
      throw InputError("voice '" + sv.name + "': resonance " + std::to_string(i) +
                       " has a non-finite or negative value");
  }
  for (const auto& c : sv.contacts) {
    if (c.size() != n) throw InputError("voice '" + sv.name + "': contact gains per resonance");
    for (auto x : c)
      if (!finite(x)) throw InputError("voice '" + sv.name + "': non-finite contact gain");
  }
}

}  // namespace

std::unique_ptr<ShakerBank::PreparedVoice> ShakerBank::prepare_voice(const ShakerVoice& sv) {
  check_voice(sv);
  auto p = std::make_unique<PreparedVoice>();
  p->params = sv.excitation;
  Voice& v = p->voice;
  v.pan[0] = sv.pan[0];
  v.pan[1] = sv.pan[1];
  v.res = sv.resonances;
  v.contacts = sv.contacts;
  for (const ShakerResonance& r : v.res) {
    v.base_hz.push_back(r.omega_d / (2.0 * std::numbers::pi));
    v.varies = v.varies || r.vary != 0 || r.sweep != 1;
  }
  v.hz = v.base_hz;
  return p;
}

// `count` consecutive slots: the first freed run that holds them, else the lease's untouched
// end; ~0u when neither does.
uint32_t ShakerBank::take_slots(uint32_t count) noexcept {
  if (const uint32_t at = free_runs_.take(count); at != ~0u) return at;
  if (uint64_t{slot_end_} + count > lease_.end) return ~0u;
  const uint32_t at = slot_end_;
  slot_end_ += count;
  fb_.set_used(lease_, slot_end_ - lease_.begin);
  return at;
}

// Returns a run, merged with its neighbours (at most one run per removed voice: the reserved
// capacity holds them all).
void ShakerBank::give_slots(uint32_t first, uint32_t count) noexcept {
  free_runs_.give(first, count);
}

bool ShakerBank::add_voice(PreparedVoice& p, uint32_t index) {
  const uint32_t n = static_cast<uint32_t>(p.voice.res.size());
  if (index >= opt_.max_voices || index > voices_.size() ||
      (index < voices_.size() && voices_[index].live) || n == 0)
    return false;
  const bool fresh = index == voices_.size();
  const uint32_t first = take_slots(n);
  if (first == ~0u) return false;
  if (fresh)
    voices_.push_back(std::move(p.voice));
  else
    std::swap(voices_[index], p.voice);
  Voice& v = voices_[index];
  v.live = true;
  v.first_slot = first;
  v.collisions_before = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const ShakerResonance& r = v.res[i];
    const float g[2] = {r.gain * v.pan[0], r.gain * v.pan[1]};
    fb_.set_mode(first + i, pole(r.omega_d, r.decay, opt_.sample_rate), g);
    fb_.set_input(first + i, index, v.contacts.empty() ? r.input : v.contacts[0][i]);
  }
  PhisemState st;
  st.key = phisem_key(opt_.seed, index);
  if (gpu_) {
    gpu_->param_data()[index] = p.params;
    gpu_->state_data()[index] = st;
    gpu_->voices = std::max(gpu_->voices, index + 1);
  } else if (fresh) {
    states_.push_back(st);
    input_.resize(std::size_t(index + 1) * fb_.max_frames());
  } else {
    states_[index] = st;
  }
  if (fresh)
    params_.push_back(p.params);
  else
    params_[index] = p.params;
  return true;
}

void ShakerBank::remove_voice(int voice) noexcept {
  if (!live(voice)) return;
  Voice& v = voices_[voice];
  const uint32_t n = static_cast<uint32_t>(v.res.size());
  for (uint32_t i = 0; i < n; ++i) fb_.clear_mode(v.first_slot + i);
  give_slots(v.first_slot, n);
  v.live = false;
  v.varies = false;
  // Silent from now on: no gain, no energy (its stream drives no slot any more either).
  params_[voice].gain = 0;
  PhisemState& st = state_ref(voice);
  st.energy = st.level = st.x1 = st.x2 = 0;
  if (gpu_) gpu_->param_data()[voice].gain = 0;
  std::size_t kept = 0;
  for (std::size_t k = 0; k < shake_count_; ++k)
    if (shakes_[k].voice != static_cast<uint32_t>(voice)) shakes_[kept++] = shakes_[k];
  shake_count_ = kept;
}

}  // namespace chladni::runtime
