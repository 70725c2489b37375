#include "chladni/runtime/modal/synth.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

#include "chladni/core/error.hpp"
#include "chladni/runtime/modal/contact_weight.hpp"

namespace chladni::runtime {
namespace {
constexpr uint32_t kGroup = 256;
constexpr int64_t kNever = std::numeric_limits<int64_t>::max();
}  // namespace

Synth::Synth(Filterbank& fb, const SynthOptions& o)
    : fb_(fb),
      opt_(o),
      threshold_(std::pow(10.0, o.retire_db / 20.0)),
      forces_(o.sample_rate, o.max_contact_modes, o.max_contacts) {
  if (!(o.sample_rate > 0) || !std::isfinite(o.sample_rate)) {
    throw InputError("sample rate must be a positive number");
  }
  if (!(o.retire_db < 0)) throw InputError("retire threshold must be below 0 dB");
  budget_ = o.max_modes ? std::min(o.max_modes, fb.unleased()) : fb.unleased();
  if (budget_ == 0) throw InputError("the filterbank has no slots left for the synth's voices");
  lease_ = fb.lease(budget_);
  voices_.resize(o.max_voices);
  slot_voice_.assign(budget_, -1);
  slot_mode_.assign(budget_, 0);
  env_.assign(budget_, 0.0f);
  peak_.assign(budget_, 0.0f);
  rate_.assign(budget_, 0.0f);
  env_time_.assign(budget_, 0);
  retire_at_.assign(budget_, kNever);
  free_heap_.resize(budget_);
  for (uint32_t s = 0; s < budget_; ++s) free_heap_[s] = s;  // sorted: already a min-heap
  group_used_.assign((budget_ + kGroup - 1) / kGroup, 0);
  steal_scratch_.reserve(budget_);
  pending_.resize(fb.max_excitations());
  fb_.set_used(lease_, 0);
  if (fb.latency() > 0) {
    const std::size_t ch = static_cast<std::size_t>(fb.channels());
    force_block_.assign(std::size_t{fb.max_frames()} * ch, 0.0f);
    force_delay_.assign((std::size_t{fb.latency()} + fb.max_frames()) * ch, 0.0f);
  }
}

Synth::~Synth() {
  for (uint32_t s = 0; s < budget_; ++s)
    if (slot_voice_[s] >= 0) fb_.clear_mode(lease_.begin + s);
  fb_.set_used(lease_, 0);
  fb_.release(lease_);
}

void Synth::render_forces(uint32_t frames, float* out) {
  if (force_delay_.empty()) {
    forces_.render(now_, frames, fb_.channels(), out, &Synth::contact_gains, this);
    return;
  }
  const std::size_t n = std::size_t{frames} * fb_.channels(), size = force_delay_.size();
  const std::size_t lag = std::size_t{fb_.latency()} * fb_.channels();
  std::fill_n(force_block_.begin(), n, 0.0f);
  forces_.render(now_, frames, fb_.channels(), force_block_.data(), &Synth::contact_gains, this);
  for (std::size_t i = 0; i < n; ++i) {  // what was written `lag` samples ago
    float& slot = force_delay_[(delay_head_ + i) % size];
    out[i] += slot;
    slot = 0.0f;
  }
  for (std::size_t i = 0; i < n; ++i)
    force_delay_[(delay_head_ + lag + i) % size] = force_block_[i];
  delay_head_ = (delay_head_ + n) % size;
}

Synth::Voice& Synth::voice(VoiceId id) {
  if (id < 0 || static_cast<std::size_t>(id) >= voices_.size() || !voices_[id].alive) {
    throw std::invalid_argument("unknown voice id " + std::to_string(id));
  }
  return voices_[id];
}

int Synth::slot_of(VoiceId id, std::size_t mode) const {
  const int32_t s = voices_.at(id).slot.at(mode);
  return s < 0 ? s : static_cast<int>(lease_.begin) + s;
}

Synth::VoiceData Synth::prepare_voice(std::span<const ModeSpec> modes) {
  for (std::size_t i = 0; i < modes.size(); ++i) {
    const ModeSpec& m = modes[i];
    if (!std::isfinite(m.omega_d) || m.omega_d < 0 || !std::isfinite(m.decay) || m.decay < 0 ||
        !std::isfinite(m.gain)) {
      throw InputError("voice mode " + std::to_string(i) +
                       ": frequency, decay and gain must be finite and non-negative");
    }
  }
  VoiceData d;
  d.modes.assign(modes.begin(), modes.end());
  d.slot.assign(modes.size(), -1);
  d.kicked.assign(modes.size(), 0);
  d.strike_amp.assign(modes.size(), {0.0f, 0.0f});
  return d;
}

Synth::VoiceId Synth::start_voice(VoiceData& data) noexcept {
  for (std::size_t v = 0; v < voices_.size(); ++v) {
    if (!voices_[v].alive) {
      Voice& voice = voices_[v];
      std::swap(static_cast<VoiceData&>(voice), data);
      voice.alive = true;
      voice.pan[0] = voice.pan[1] = 1.0f;
      return static_cast<VoiceId>(v);
    }
  }
  return -1;
}

Synth::VoiceId Synth::start_voice(std::span<const ModeSpec> modes) {
  VoiceData data = prepare_voice(modes);
  const VoiceId id = start_voice(data);
  if (id < 0)
    throw std::runtime_error("no free voice (max_voices = " + std::to_string(voices_.size()) + ")");
  return id;
}

void Synth::apply_gains(uint32_t slot) {
  const Voice& v = voices_[slot_voice_[slot]];
  const float g = v.modes[slot_mode_[slot]].gain;
  const float gains[2] = {g * v.pan[0], g * v.pan[1]};
  fb_.set_gains(lease_.begin + slot, gains);
}

void Synth::set_pan(VoiceId id, float left, float right) {
  Voice& v = voice(id);
  if (!std::isfinite(left) || !std::isfinite(right)) throw InputError("pan gains must be finite");
  v.pan[0] = left;
  v.pan[1] = right;
  for (int32_t s : v.slot) {
    if (s >= 0) apply_gains(static_cast<uint32_t>(s));
  }
}

void Synth::set_mode_gains(VoiceId id, std::span<const float> gains) {
  Voice& v = voice(id);
  if (gains.size() != v.modes.size()) throw std::invalid_argument("set_mode_gains: wrong count");
  for (std::size_t i = 0; i < gains.size(); ++i) {
    if (!std::isfinite(gains[i]))
      throw InputError("mode gain " + std::to_string(i) + " is not finite");
    v.modes[i].gain = gains[i];
    if (v.slot[i] >= 0) apply_gains(static_cast<uint32_t>(v.slot[i]));
  }
}

uint32_t Synth::allocate_slot() {
  if (free_heap_.empty()) return ~0u;
  std::pop_heap(free_heap_.begin(), free_heap_.end(), std::greater<>());
  const uint32_t s = free_heap_.back();
  free_heap_.pop_back();  // capacity stays: no allocation later
  ++used_;
  ++group_used_[s / kGroup];
  high_water_ = std::max(high_water_, (s / kGroup + 1) * kGroup);
  return s;
}

void Synth::free_slot(uint32_t s) {
  Voice& v = voices_[slot_voice_[s]];
  v.slot[slot_mode_[s]] = -1;
  slot_voice_[s] = -1;
  retire_at_[s] = kNever;
  fb_.clear_mode(lease_.begin + s);
  free_heap_.push_back(s);
  std::push_heap(free_heap_.begin(), free_heap_.end(), std::greater<>());
  --used_;
  --group_used_[s / kGroup];
}

void Synth::drop_pending(uint32_t slot) {
  std::size_t w = 0;
  for (std::size_t r = 0; r < pending_count_; ++r) {
    if (pending_[r].slot != lease_.begin + slot) pending_[w++] = pending_[r];
  }
  pending_count_ = w;
}

double Synth::envelope(uint32_t s, int64_t t) const {
  // |z(t)| <= env * exp(-rate (t - env_time)).
  return env_[s] * std::exp(-double(rate_[s]) * double(t - env_time_[s]));
}

void Synth::steal(uint32_t needed) {
  // The least audible resident modes: envelope bound now times the larger channel gain.
  steal_scratch_.clear();
  for (uint32_t s = 0; s < budget_; ++s) {
    if (slot_voice_[s] < 0) continue;
    const Voice& v = voices_[slot_voice_[s]];
    const double g =
        std::abs(v.modes[slot_mode_[s]].gain) * std::max(std::abs(v.pan[0]), std::abs(v.pan[1]));
    const double env = envelope(s, static_cast<int64_t>(now_));
    steal_scratch_.emplace_back(static_cast<float>(env * g), s);
  }
  needed = std::min<uint32_t>(needed, static_cast<uint32_t>(steal_scratch_.size()));
  std::nth_element(steal_scratch_.begin(), steal_scratch_.begin() + needed, steal_scratch_.end());
  for (uint32_t k = 0; k < needed; ++k) {
    const uint32_t s = steal_scratch_[k].second;
    drop_pending(s);
    free_slot(s);
    ++stats_.stolen;
  }
}

void Synth::excite(VoiceId id, std::span<const std::complex<float>> amp, uint32_t offset) {
  Voice& v = voice(id);
  if (amp.size() != v.modes.size()) throw std::invalid_argument("excite: wrong amplitude count");
  if (offset >= fb_.max_frames()) throw std::invalid_argument("excite: offset beyond one render");
  kick(v, id, amp, offset);
}

void Synth::kick(Voice& v, VoiceId id, std::span<const std::complex<float>> amp, uint32_t offset) {
  std::fill(v.kicked.begin(), v.kicked.begin() + amp.size(), uint8_t{0});
  // Modes whose kick is below the retire threshold of the strongest one would retire at once.
  double strongest = 0;
  uint32_t new_slots = 0;
  for (std::size_t i = 0; i < amp.size(); ++i) {
    if (!std::isfinite(amp[i].real()) || !std::isfinite(amp[i].imag())) {
      throw InputError("excitation of mode " + std::to_string(i) + " is not finite");
    }
    strongest = std::max(strongest, double(std::abs(amp[i])) * std::abs(v.modes[i].gain));
  }
  if (strongest == 0) return;
  const double floor = strongest * threshold_;
  for (std::size_t i = 0; i < amp.size(); ++i) {
    if (v.slot[i] < 0 && double(std::abs(amp[i])) * std::abs(v.modes[i].gain) > floor) ++new_slots;
  }
  if (new_slots > free_heap_.size()) steal(new_slots - static_cast<uint32_t>(free_heap_.size()));
  const int64_t t = static_cast<int64_t>(now_) + offset;
  for (std::size_t i = 0; i < amp.size(); ++i) {
    const double a = std::abs(amp[i]);
    if (a * std::abs(v.modes[i].gain) <= floor) {
      if (a > 0) ++stats_.skipped;
      continue;
    }
    if (pending_count_ == pending_.size()) {
      throw std::length_error("excite: more excitations than one render can take; render first");
    }
    int32_t s = v.slot[i];
    if (s < 0) {
      const uint32_t got = allocate_slot();
      if (got == ~0u) {  // budget exhausted even after stealing
        ++stats_.skipped;
        continue;
      }
      s = static_cast<int32_t>(got);
      v.slot[i] = s;
      slot_voice_[got] = id;
      slot_mode_[got] = static_cast<uint32_t>(i);
      const ModeSpec& m = v.modes[i];
      const float gains[2] = {m.gain * v.pan[0], m.gain * v.pan[1]};
      fb_.set_mode(lease_.begin + got, pole(m.omega_d, m.decay, opt_.sample_rate), gains);
      env_[got] = peak_[got] = 0.0f;
      env_time_[got] = t;
      rate_[got] = static_cast<float>(m.decay / opt_.sample_rate);
    }
    // Envelope bound: each kick adds its magnitude to the decayed bound.
    const double env = envelope(static_cast<uint32_t>(s), t) + a;
    env_[s] = static_cast<float>(env);
    env_time_[s] = t;
    peak_[s] = std::max(peak_[s], env_[s]);
    // Retire when env exp(-rate dt) < peak * threshold.
    const double ratio = env / (double(peak_[s]) * threshold_);
    retire_at_[s] =
        rate_[s] > 0 ? t + static_cast<int64_t>(std::ceil(std::log(ratio) / rate_[s])) : kNever;
    pending_[pending_count_++] =
        Excitation{lease_.begin + static_cast<uint32_t>(s), offset, amp[i].real(), amp[i].imag()};
    v.kicked[i] = 1;
  }
}

void Synth::strike(VoiceId id, std::span<const std::complex<float>> coupling, double start,
                   double contact) {
  Voice& v = voice(id);
  if (coupling.size() != v.modes.size()) throw std::invalid_argument("strike: wrong mode count");
  if (!(start > -1.0) || !(std::ceil(start) < fb_.max_frames()))
    throw std::invalid_argument("strike: start beyond one render");
  if (!std::isfinite(contact) || contact < 0) throw InputError("contact time must be >= 0");
  const uint32_t offset = static_cast<uint32_t>(std::ceil(start));
  const double delay = (offset - start) / opt_.sample_rate;  // contact start -> first sample
  for (std::size_t i = 0; i < coupling.size(); ++i) {
    const ModeSpec& m = v.modes[i];
    const std::complex<double> lambda(-m.decay, m.omega_d);
    const std::complex<double> w = std::complex<double>(coupling[i]) *
                                   contact_weight(1.0, contact, m.omega_d, m.decay) *
                                   std::exp(lambda * delay);
    v.strike_amp[i] = {static_cast<float>(w.real()), static_cast<float>(w.imag())};
  }
  const std::span amp(v.strike_amp.data(), coupling.size());
  kick(v, id, amp, offset);
  const double t0 = static_cast<double>(now_) + start;
  if (ContactForces::end_sample(t0, contact, opt_.sample_rate) <=
      static_cast<int64_t>(now_ + offset))
    return;  // no sample inside the contact: the kick is exact
  if (!forces_.begin(id, t0, contact)) {
    ++stats_.contacts_undriven;
    return;
  }
  bool all = true;
  for (std::size_t i = 0; i < coupling.size(); ++i) {
    if (!v.kicked[i]) continue;
    const ModeSpec& m = v.modes[i];
    all = forces_.add_mode(static_cast<uint32_t>(i), m.omega_d, m.decay,
                           std::complex<double>(coupling[i]), std::complex<double>(amp[i])) &&
          all;
  }
  if (!all) ++stats_.contacts_undriven;
}

void Synth::contact_gains(const void* self, int32_t voice, uint32_t mode, float gains[2]) {
  const Voice& v = static_cast<const Synth*>(self)->voices_[voice];
  const float g = v.modes[mode].gain;
  gains[0] = g * v.pan[0];
  gains[1] = g * v.pan[1];
}

void Synth::stop_voice(VoiceId id) {
  Voice& v = voice(id);
  for (int32_t s : v.slot) {
    if (s >= 0) {
      drop_pending(static_cast<uint32_t>(s));
      free_slot(static_cast<uint32_t>(s));
    }
  }
  forces_.drop_voice(id);
  v.alive = false;
}

void Synth::render(uint32_t frames, float* out, const DriveInput& drive) {
  while (high_water_ > 0 && group_used_[high_water_ / kGroup - 1] == 0) high_water_ -= kGroup;
  fb_.set_used(lease_, high_water_);
  fb_.process(std::span(pending_.data(), pending_count_), frames, out, drive);
  pending_count_ = 0;
  render_forces(frames, out);
  now_ += frames;
  // Retire a round-robin share of the resident range (each slot is visited within ~8 renders).
  const uint32_t range = std::min(high_water_, budget_);
  const uint32_t scan = std::min(range, std::max<uint32_t>(4096, range / 8));
  const int64_t now = static_cast<int64_t>(now_);
  for (uint32_t k = 0; k < scan; ++k) {
    if (scan_cursor_ >= range) scan_cursor_ = 0;
    const uint32_t s = scan_cursor_++;
    if (slot_voice_[s] >= 0 && retire_at_[s] <= now) {
      free_slot(s);
      ++stats_.retired;
    }
  }
}

}  // namespace chladni::runtime
