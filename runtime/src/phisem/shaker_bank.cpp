#include "chladni/runtime/phisem/shaker_bank.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <thread>

#include "chladni/core/error.hpp"
#include "chladni/core/random.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/modal/object_modes.hpp"
#include "shaker_gpu_stage.hpp"

namespace chladni::runtime {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Random in [-1, 1) for retuning resonance j after the block that started at `counter`.
double retune_noise(uint32_t key, uint32_t counter, uint32_t j) {
  const uint32_t h = pcg_hash(pcg_hash(counter ^ 0xa511e9b3u) ^ key ^ pcg_hash(j + 0x68e31da4u));
  return 2.0 * unit_float(h) - 1.0;
}

}  // namespace

ShakerVoice instrument_voice(const PhisemPreset& preset, double fs, double objects) {
  ShakerVoice v;
  v.name = preset.name;
  v.excitation = phisem_params(preset, fs, objects);
  for (const PhisemResonance& r : preset.resonances) {
    if (!(r.frequency > 0 && r.frequency < 0.5 * fs)) {
      throw InputError("instrument '" + preset.name + "': resonance at " +
                       std::to_string(r.frequency) + " Hz is not below Nyquist at " +
                       std::to_string(fs) + " Hz");
    }
    if (!(r.radius > 0 && r.radius < 1))
      throw InputError("instrument '" + preset.name + "': pole radius must be in (0, 1)");
    ShakerResonance s;
    s.omega_d = kTwoPi * r.frequency;
    s.decay = -std::log(r.radius) * kPhisemReferenceRate;  // radius^(per) per sample
    const double theta = s.omega_d / fs;
    // STK's two-pole resonance as the slot's Im(z): kick g e^{i theta} / sin(theta) per input.
    const std::complex<double> kick = r.gain * std::polar(1.0, theta) / std::sin(theta);
    s.input = std::complex<float>(kick);
    s.gain = 1.0f;
    if (r.vary) {
      s.vary = preset.vary;
      s.sweep = std::pow(preset.sweep, kPhisemReferenceRate);  // per reference sample -> per second
    }
    v.resonances.push_back(s);
  }
  return v;
}

ShakerVoice object_voice(const PhisemPreset& preset, const ObjectModes& object, double fs,
                         double impulse, std::size_t contacts, uint64_t seed, double objects) {
  if (!object.model || !object.model->has_geometry())
    throw InputError("shaking an object needs a soundbank with surface mode shapes");
  if (!(std::isfinite(impulse) && impulse > 0))
    throw InputError("impulse per unit of excitation must be finite and > 0 (N*s)");
  if (contacts == 0) throw InputError("an object voice needs at least one contact point");
  const ModalModel& m = *object.model;
  ShakerVoice v;
  v.name = preset.name + " on " + m.name;
  v.excitation = phisem_params(preset, fs, objects);
  for (const ModeSpec& s : object.modes) {
    ShakerResonance r;
    r.omega_d = s.omega_d;
    r.decay = s.decay;
    r.gain = s.gain;
    r.input = {0, 0};
    v.resonances.push_back(r);
  }
  Rng rng(seed ^ 0x5a17c0de5eedull);
  for (std::size_t c = 0; c < contacts; ++c) {
    const std::size_t point = rng.index(static_cast<uint32_t>(m.points.size()));
    // Particles strike along the inward normal (any direction where there are no normals).
    Vec3 dir{0, 0, -1};
    if (!m.normals.empty()) dir = scale(m.normals[point], -1.0);
    std::vector<std::complex<float>> kick(object.modes.size());
    for (std::size_t i = 0; i < object.modes.size(); ++i) {
      const double wd = object.modes[i].omega_d;
      // q_i = (v_i(x) . n) J / omega_d (DESIGN.md), J = impulse per unit of excitation.
      kick[i] = wd > 0 ? static_cast<float>(dot(m.shape(i, point), dir) * impulse / wd) : 0.0f;
    }
    v.contacts.push_back(std::move(kick));
  }
  return v;
}

ShakerBank::ShakerBank(Filterbank& fb, const ShakerBankOptions& o) : fb_(fb), opt_(o) {
  static_assert(sizeof(PhisemParams) == 32, "matches kernels/phisem.comp");
  static_assert(sizeof(PhisemState) == 32, "matches kernels/phisem.comp");
  if (!(std::isfinite(o.sample_rate) && o.sample_rate > 0))
    throw InputError("sample rate must be finite and > 0");
  if (o.max_voices == 0) throw InputError("a shaker bank needs max_voices > 0");
  voices_.reserve(o.max_voices);
  params_.reserve(o.max_voices);
  free_runs_.reserve(std::size_t{o.max_voices} + 1);
  shakes_.resize(o.max_shakes);
  if (o.excitation == ExcitationBackend::Gpu) {
    GpuFilterbank* gfb = fb.device();
    if (!gfb) throw InputError("a GPU excitation needs the GPU filterbank");
    if (gfb->max_streams() < o.max_voices) {
      throw InputError("the GPU filterbank has " + std::to_string(gfb->max_streams()) +
                       " input streams, fewer than the bank's " + std::to_string(o.max_voices) +
                       " voices");
    }
    gpu_ = std::make_unique<GpuStage>(*gfb, o.max_voices, o.max_shakes);
    gfb->set_input_stage(gpu_.get());
    backend_name_ = "gpu";
  } else {
    states_.reserve(o.max_voices);
    if (o.reserve_all) input_.reserve(std::size_t{o.max_voices} * fb.max_frames());
    const int threads =
        o.threads > 0 ? o.threads : std::max(1, int(std::thread::hardware_concurrency()));
    pool_ = std::make_unique<ThreadPool>(threads);
    tasks_ = threads == 1 ? 1 : 4 * threads;  // small tasks even out voices of unequal work
    backend_name_ = "cpu";
  }
  lease_ = fb.lease(o.slots ? o.slots : fb.unleased());
  slot_end_ = lease_.begin;
}

ShakerBank::~ShakerBank() {
  if (gpu_) gpu_->fb_.set_input_stage(nullptr);  // before the stage goes
  for (uint32_t s = lease_.begin; s < slot_end_; ++s) fb_.clear_mode(s);
  fb_.set_used(lease_, 0);
  fb_.release(lease_);
}

int ShakerBank::add_voice(const ShakerVoice& sv) {
  std::unique_ptr<PreparedVoice> p = prepare_voice(sv);
  uint32_t index = 0;
  while (index < voices_.size() && voices_[index].live) ++index;
  if (index >= opt_.max_voices)
    throw InputError("shaker bank is full (" + std::to_string(opt_.max_voices) + " voices)");
  if (!add_voice(*p, index)) {
    const uint32_t room = std::max(lease_.end - slot_end_, free_runs_.largest());
    throw InputError("voice '" + sv.name + "' needs " + std::to_string(sv.resonances.size()) +
                     " filterbank slots; only " + std::to_string(room) + " are left");
  }
  return static_cast<int>(index);
}

bool ShakerBank::shake(int voice, float amount, uint32_t offset) {
  if (!live(voice) || !std::isfinite(amount) || amount < 0 || offset >= fb_.max_frames() ||
      shake_count_ >= shakes_.size())
    return false;
  shakes_[shake_count_++] = Shake{static_cast<uint32_t>(voice), offset, amount};
  return true;
}

void ShakerBank::set_gains(int voice, std::span<const float> gains, float left, float right) {
  Voice& v = voices_.at(static_cast<std::size_t>(voice));
  for (std::size_t i = 0; i < v.res.size() && i < gains.size(); ++i) {
    const float g[2] = {gains[i] * left, gains[i] * right};
    fb_.set_gains(v.first_slot + static_cast<uint32_t>(i), g);
  }
}

PhisemState& ShakerBank::state_ref(int voice) {
  return gpu_ ? gpu_->state_data()[voice] : states_[voice];
}

PhisemState ShakerBank::state(int voice) const {
  return const_cast<ShakerBank*>(this)->state_ref(voice);
}

DriveInput ShakerBank::prepare(uint32_t frames) {
  if (frames == 0) return DriveInput{};
  const uint32_t nv = voice_count();
  // A shake queued for a later sample than this (shorter) block has lands on its last sample.
  Shake* sh = shakes_.data();
  for (std::size_t k = 0; k < shake_count_; ++k) sh[k].offset = std::min(sh[k].offset, frames - 1);
  std::sort(sh, sh + shake_count_, [](const Shake& a, const Shake& b) {
    return a.voice != b.voice ? a.voice < b.voice : a.offset < b.offset;
  });
  // A shake moves an object voice's contact to a random surface point.
  for (std::size_t k = 0; k < shake_count_; ++k) {
    if (k > 0 && sh[k].voice == sh[k - 1].voice) continue;
    Voice& v = voices_[sh[k].voice];
    if (v.contacts.size() > 1) {
      const PhisemState& st = state_ref(static_cast<int>(sh[k].voice));
      const uint32_t c = pcg_hash(st.key ^ pcg_hash(st.counter + sh[k].offset + 0x3c6ef372u)) %
                         static_cast<uint32_t>(v.contacts.size());
      for (std::size_t i = 0; i < v.res.size(); ++i)
        fb_.set_input(v.first_slot + static_cast<uint32_t>(i), sh[k].voice, v.contacts[c][i]);
    }
  }
  for (uint32_t i = 0; i < nv; ++i) voices_[i].collisions_before = state_ref(int(i)).collisions;
  if (gpu_) {
    uint32_t* dst = gpu_->shake_data();
    uint32_t count = 0;
    for (std::size_t k = 0; k < shake_count_; ++k) {
      uint32_t bits;
      std::memcpy(&bits, &sh[k].amount, 4);
      const uint32_t e[4] = {sh[k].voice, sh[k].offset, bits, 0};
      std::memcpy(dst + 4 * count++, e, sizeof(e));
    }
    gpu_->shake_count = count;
    shake_count_ = 0;
    return DriveInput{nullptr, nv};
  }
  frames_ = frames;
  pool_->run(&ShakerBank::generate_task, this, tasks_);
  shake_count_ = 0;
  return DriveInput{input_.data(), nv};
}

void ShakerBank::generate_task(void* self_ptr, int task) {
  auto* self = static_cast<ShakerBank*>(self_ptr);
  const uint32_t nv = self->voice_count(), frames = self->frames_;
  const uint32_t v0 = static_cast<uint32_t>(uint64_t{nv} * task / self->tasks_);
  const uint32_t v1 = static_cast<uint32_t>(uint64_t{nv} * (task + 1) / self->tasks_);
  const Shake* sh = self->shakes_.data();
  const Shake* end = sh + self->shake_count_;
  const Shake* k =
      std::lower_bound(sh, end, v0, [](const Shake& s, uint32_t v) { return s.voice < v; });
  for (uint32_t i = v0; i < v1; ++i) {
    const Shake* e = k;
    while (e != end && e->voice == i) ++e;
    phisem_generate(self->params_[i], self->states_[i], std::span<const Shake>(k, e), frames,
                    self->input_.data() + std::size_t(i) * frames);
    k = e;
  }
}

void ShakerBank::retune(Voice& v, const PhisemState& st, uint32_t frames) {
  const bool collided = st.collisions != v.collisions_before;
  for (std::size_t j = 0; j < v.res.size(); ++j) {
    const ShakerResonance& r = v.res[j];
    double hz = v.hz[j];
    if (collided && r.vary != 0) {
      // Cook's random retuning per collision, here per block with collisions (the filterbank
      // changes poles between blocks); counter - frames is the block's first sample.
      hz = v.base_hz[j] *
           (1.0 + r.vary * retune_noise(st.key, st.counter - frames, static_cast<uint32_t>(j)));
    } else if (r.sweep != 1) {
      hz *= std::pow(r.sweep, frames / opt_.sample_rate);
    }
    hz = std::min(hz, 0.49 * opt_.sample_rate);  // a sweep stops below Nyquist
    if (hz == v.hz[j]) continue;
    v.hz[j] = hz;
    fb_.set_pole(v.first_slot + static_cast<uint32_t>(j),
                 pole(kTwoPi * hz, r.decay, opt_.sample_rate));
  }
}

void ShakerBank::finish(uint32_t frames) {
  for (uint32_t i = 0; i < voice_count(); ++i) {
    Voice& v = voices_[i];
    if (v.varies) retune(v, state_ref(int(i)), frames);
  }
}

void ShakerBank::render(uint32_t frames, float* out) {
  const DriveInput in = prepare(frames);
  fb_.process({}, frames, out, in);
  finish(frames);
}

std::vector<TimedShake> regular_shakes(uint32_t voices, double rate, double until, float amount) {
  if (!(std::isfinite(rate) && rate > 0 && rate <= 1000))
    throw InputError("shakes per second must lie in (0, 1000]");
  if (!(std::isfinite(amount) && amount > 0 && amount <= 1))
    throw InputError("shake energy must lie in (0, 1]");
  std::vector<TimedShake> out;
  for (uint64_t k = 0;; ++k) {
    const double t0 = double(k) / rate;
    if (t0 >= until) break;
    for (uint32_t v = 0; v < voices; ++v) {
      const double t = t0 + double(v) / (rate * voices);
      if (t < until) out.push_back({t, static_cast<int>(v), amount});
    }
  }
  return out;
}

AudioBuffer render_shaker(ShakerBank& bank, int channels, double fs,
                          std::span<const TimedShake> events, double seconds, uint32_t block) {
  if (!(std::isfinite(seconds) && seconds > 0 && seconds <= 3600))
    throw InputError("duration must lie in (0, 3600] s");
  if (block == 0) throw InputError("block size must be > 0");
  const uint64_t total = static_cast<uint64_t>(std::ceil(seconds * fs));
  AudioBuffer audio;
  audio.sample_rate = static_cast<int>(fs);
  audio.channels = channels;
  audio.samples.resize(total * channels);
  std::size_t next = 0;
  for (uint64_t t = 0; t < total; t += block) {
    const uint32_t frames = static_cast<uint32_t>(std::min<uint64_t>(block, total - t));
    for (; next < events.size(); ++next) {
      const double at = std::round(events[next].time * fs);
      if (at >= double(t + frames)) break;
      const uint32_t offset = at <= double(t) ? 0 : static_cast<uint32_t>(at - double(t));
      bank.shake(events[next].voice, events[next].amount, offset);
    }
    bank.render(frames, audio.samples.data() + t * channels);
  }
  return audio;
}

}  // namespace chladni::runtime
