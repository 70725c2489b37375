#include "chladni/runtime/render.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <thread>

#include "chladni/core/error.hpp"
#include "chladni/runtime/gpu_filterbank.hpp"
#include "chladni/runtime/shaker_bank.hpp"
#include "chladni/runtime/thread_pool.hpp"
#include "chladni/runtime/transfer_gains.hpp"

namespace chladni::runtime {
namespace {

// Spherical spreading relative to 1 m, clamped so an object at the listener stays finite.
constexpr double kMinDistance = 0.1;
// Listener-gain tables this large spread their updates over all cores.
constexpr std::size_t kThreadedGainModes = 4096;
// Surface points each shaken object's particles move between.
constexpr std::size_t kShakeContacts = 8;

bool same_voice(const ShakeEvent& a, const ShakeEvent& b) {
  return a.object == b.object && a.instrument == b.instrument &&
         a.resonate_object == b.resonate_object && a.particles == b.particles &&
         a.impulse == b.impulse;
}

// The voice of a shake event: the object's modes driven by the instrument's particles, or the
// instrument's own resonances.
ShakerVoice shake_voice(const ShakeEvent& ev, const ObjectModes& obj, double fs, uint64_t seed) {
  try {
    const PhisemPreset& preset = phisem_preset(ev.instrument);
    if (!ev.resonate_object) return instrument_voice(preset, fs, ev.particles);
    if (obj.model && obj.model->has_geometry())
      return object_voice(preset, obj, fs, ev.impulse, kShakeContacts, seed, ev.particles);
    // Inline modes carry their pressure per N*s; a model without geometry its 1 / omega_d.
    ShakerVoice v;
    v.name = preset.name;
    v.excitation = phisem_params(preset, fs, ev.particles);
    for (std::size_t i = 0; i < obj.modes.size(); ++i) {
      const ModeSpec& m = obj.modes[i];
      const double per_ns = obj.inline_modes ? (*obj.inline_modes)[i].amplitude
                            : m.omega_d > 0  ? 1.0 / m.omega_d
                                             : 0.0;
      v.resonances.push_back(
          {m.omega_d, m.decay, {static_cast<float>(per_ns * ev.impulse), 0.0f}, m.gain, 0, 1});
    }
    return v;
  } catch (const InputError& e) {
    throw InputError(ev.json_path + ": " + e.what());
  }
}

}  // namespace

SceneShakers scene_shakers(const Scene& scene, const std::vector<ObjectModes>& objects,
                           uint64_t seed) {
  SceneShakers out;
  for (std::size_t e = 0; e < scene.shakes.size(); ++e) {
    const ShakeEvent& ev = scene.shakes[e];
    int v = 0;
    while (v < static_cast<int>(out.first_event.size()) &&
           !same_voice(scene.shakes[out.first_event[v]], ev))
      ++v;
    if (v == static_cast<int>(out.first_event.size())) {
      out.first_event.push_back(e);
      out.voices.push_back(shake_voice(ev, objects.at(ev.object), scene.sample_rate, seed + v));
      out.slots += static_cast<uint32_t>(out.voices.back().resonances.size());
    }
    out.voice.push_back(v);
  }
  return out;
}

ObjectModes object_modes(const ModalModel& model) {
  model.validate();
  ObjectModes o;
  o.model = &model;
  if (model.transfer) o.transfer = &*model.transfer;
  for (std::size_t i = 0; i < model.mode_count(); ++i) {
    const double wd = model.damped_omega(i);
    o.modes.push_back({wd, model.decay[i], static_cast<float>(model.radiation[i] * wd * wd)});
  }
  return o;
}

ObjectModes object_modes(const std::vector<InlineMode>& modes) {
  ObjectModes o;
  o.inline_modes = &modes;
  for (const InlineMode& m : modes)
    o.modes.push_back({2.0 * std::numbers::pi * m.frequency, m.decay, 1.0f});
  return o;
}

void impact_coupling(const ObjectModes& object, const ImpactEvent& ev,
                     std::vector<std::complex<float>>& out) {
  out.resize(object.modes.size());
  std::size_t point = 0;
  if (object.model && object.model->has_geometry()) {
    if (ev.vertex) {
      if (*ev.vertex >= object.model->points.size()) {
        throw InputError(ev.json_path + ".vertex: " + std::to_string(*ev.vertex) +
                         " is out of range (object has " +
                         std::to_string(object.model->points.size()) + " surface points)");
      }
      point = *ev.vertex;
    } else if (ev.point) {
      point = object.model->nearest_point(*ev.point);
    }
  }
  for (std::size_t i = 0; i < object.modes.size(); ++i) {
    const ModeSpec& m = object.modes[i];
    double w = ev.impulse;
    if (object.inline_modes) {
      w *= (*object.inline_modes)[i].amplitude;
    } else if (object.model) {
      // q_i = (v_i(x) . n) J / omega_d ... (DESIGN.md)
      const double vn =
          object.model->has_geometry() ? dot(object.model->shape(i, point), ev.direction) : 1.0;
      w *= m.omega_d > 0 ? vn / m.omega_d : 0.0;
    }
    out[i] = std::complex<float>(static_cast<float>(w), 0.0f);
  }
}

AudioBuffer render_scene(const Scene& scene, const std::vector<ObjectModes>& objects,
                         Filterbank& fb, const RenderOptions& options, RenderReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  if (objects.size() != scene.objects.size()) throw InternalError("render: object count mismatch");
  if (fb.channels() != scene.channels) throw InternalError("render: channel count mismatch");
  const double fs = scene.sample_rate;
  const uint32_t block = std::min(options.block, fb.max_frames());
  if (block == 0) throw InputError("block size must be > 0");
  SynthOptions so = options.synth;
  so.sample_rate = fs;
  so.max_voices = std::max<uint32_t>(so.max_voices, static_cast<uint32_t>(objects.size()));
  // Shake events: their voices take the slots above the synth's budget.
  const SceneShakers shakers = scene_shakers(scene, objects, options.seed);
  std::unique_ptr<ShakerBank> bank;
  if (!shakers.first_event.empty()) {
    if (fb.capacity() <= shakers.slots)
      throw InternalError("render: the filterbank has no room for the scene's shakers");
    const uint32_t room = fb.capacity() - shakers.slots;
    so.max_modes = so.max_modes ? std::min(so.max_modes, room) : room;
    so.reserved_end = so.max_modes + shakers.slots;
    ShakerBankOptions bo;
    bo.sample_rate = fs;
    bo.first_slot = so.max_modes;
    bo.max_voices = static_cast<uint32_t>(shakers.first_event.size());
    bo.seed = options.seed;
    bo.excitation =
        dynamic_cast<GpuFilterbank*>(&fb) ? ExcitationBackend::Gpu : ExcitationBackend::Cpu;
    bank = std::make_unique<ShakerBank>(fb, bo);
    for (const ShakerVoice& v : shakers.voices) bank->add_voice(v);
  }
  Synth synth(fb, so);

  std::vector<Synth::VoiceId> voices;
  for (const ObjectModes& obj : objects) voices.push_back(synth.start_voice(obj.modes));

  // Poses change with move events; transfer gains for all objects that have transfer at once.
  Listener listener = scene.listener;
  std::vector<Vec3> position;
  std::vector<Quat> orientation;
  for (const SceneObject& so_k : scene.objects) {
    position.push_back(so_k.position);
    orientation.push_back(so_k.orientation);
  }
  // Objects that share a soundbank share its coefficients and far-field maps.
  std::size_t transfer_modes = 0;
  for (const ObjectModes& obj : objects)
    if (obj.transfer) transfer_modes += obj.transfer->mode_count();
  const bool gpu_table = options.gain_device && transfer_modes >= options.gpu_gain_modes;
  ThreadPool pool(transfer_modes >= kThreadedGainModes
                      ? int(std::max(1u, std::thread::hardware_concurrency()))
                      : 1);
  TransferTable table;
  // Maps pay for their build once many modes are updated; the device streams the series.
  if (gpu_table || transfer_modes < options.map_gain_modes) table.map_options.reset();
  std::vector<int> table_object(objects.size(), -1);
  for (std::size_t k = 0; k < objects.size(); ++k) {
    if (!objects[k].transfer) continue;
    if (objects[k].transfer->mode_count() != objects[k].modes.size())
      throw InternalError("render: transfer and modes differ in count");
    std::size_t same = 0;
    while (same < k && objects[same].transfer != objects[k].transfer) ++same;
    table_object[k] = static_cast<int>(same < k ? table.add_instance(table_object[same])
                                                : table.add(*objects[k].transfer, &pool));
  }
  ListenerFrame frame;
  std::vector<Vec3> listener_local(table.objects.size());
  std::vector<float> table_gains(table.mode_count()), gains;
  std::unique_ptr<GpuTransferGains> gpu_gains;
  if (gpu_table) gpu_gains = std::make_unique<GpuTransferGains>(options.gain_device, table);
  RenderReport rep;
  rep.gain_backend = table.mode_count() == 0 ? "" : gpu_gains ? "gpu" : "cpu";
  auto update_gains = [&] {
    const auto g0 = std::chrono::steady_clock::now();
    for (std::size_t k = 0; k < objects.size(); ++k) {
      if (table_object[k] >= 0)
        listener_local[table_object[k]] =
            rotate_inverse(orientation[k], sub(listener.position, position[k]));
    }
    if (table.mode_count() > 0) {
      frame.update(table, listener_local, gpu_gains != nullptr);
      if (gpu_gains)
        gpu_gains->compute(frame, table_gains);
      else
        transfer_gains(table, frame, table_gains, &pool);
    }
    // Listener frame: right = forward x up.
    const Vec3 right = cross(listener.forward, listener.up);
    const double rn = std::sqrt(dot(right, right));
    for (std::size_t k = 0; k < objects.size(); ++k) {
      const Vec3 d = sub(position[k], listener.position);
      const double r = std::sqrt(dot(d, d));
      const double g = scene.gain * scene.objects[k].gain;
      gains.resize(objects[k].modes.size());
      const double spread = g / std::max(r, kMinDistance);
      const Transfer* xfer = objects[k].transfer;
      const float* src = table_object[k] >= 0
                             ? table_gains.data() + table.objects[table_object[k]].first_mode
                             : nullptr;
      for (std::size_t i = 0; i < gains.size(); ++i) {
        // Transfer where its fit is usable, else the compact-source estimate over distance.
        gains[i] = src && xfer->usable(i) ? static_cast<float>(g * src[i])
                                          : static_cast<float>(objects[k].modes[i].gain * spread);
      }
      synth.set_mode_gains(voices[k], gains);
      float pan[2] = {1.0f, 1.0f};
      if (scene.channels == 2) {
        const double s = r > 1e-9 && rn > 0 ? std::clamp(dot(d, right) / (r * rn), -1.0, 1.0) : 0.0;
        const double theta = (s + 1.0) * std::numbers::pi / 4.0;  // constant-power pan
        pan[0] = static_cast<float>(std::cos(theta));
        pan[1] = static_cast<float>(std::sin(theta));
        synth.set_pan(voices[k], pan[0], pan[1]);
      }
      // Shakers on this object: its mode gains, or plain spreading for an instrument's own.
      for (std::size_t v = 0; bank && v < shakers.first_event.size(); ++v) {
        const ShakeEvent& ev = scene.shakes[shakers.first_event[v]];
        if (ev.object != k) continue;
        if (ev.resonate_object) {
          bank->set_gains(static_cast<int>(v), gains, pan[0], pan[1]);
        } else {
          const std::vector<float> flat(shakers.voices[v].resonances.size(),
                                        static_cast<float>(spread));
          bank->set_gains(static_cast<int>(v), flat, pan[0], pan[1]);
        }
      }
    }
    ++rep.gain_updates;
    rep.gain_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - g0).count();
  };
  update_gains();

  double last_event = scene.events.empty() ? 0.0 : scene.events.back().time;
  if (!scene.shakes.empty()) {
    // A shaken voice sounds while its energy lasts and then rings with its slowest resonance.
    double ring = 0;
    for (const ShakerVoice& v : shakers.voices) {
      const PhisemParams& p = v.excitation;
      double slowest = 1e9;
      for (const ShakerResonance& r : v.resonances)
        slowest = std::min(slowest, std::max(r.decay, 1e-3));
      const double energy_s = p.system_decay < 1
                                  ? std::log(kPhisemMinEnergy) / std::log(p.system_decay) / fs
                                  : options.max_tail;
      ring = std::max(ring, energy_s + std::log(1e5) / slowest);  // to -100 dB
    }
    last_event = std::max(last_event, scene.shakes.back().time + std::min(ring, options.max_tail));
  }
  const uint64_t limit = static_cast<uint64_t>(
      std::ceil((scene.duration ? *scene.duration : last_event + options.max_tail) * fs));
  AudioBuffer audio;
  audio.sample_rate = scene.sample_rate;
  audio.channels = scene.channels;
  audio.samples.reserve(static_cast<std::size_t>(std::min<uint64_t>(limit, 1ull << 28)) *
                        scene.channels);
  std::vector<float> buf(static_cast<std::size_t>(block) * scene.channels);
  std::vector<std::complex<float>> amps;
  std::size_t next = 0, next_move = 0, next_shake = 0;
  uint64_t t = 0;
  while (t < limit) {
    uint32_t frames = static_cast<uint32_t>(std::min<uint64_t>(block, limit - t));
    // Moves take effect at their first sample: apply those due, end the block before the next.
    bool moved = false;
    while (next_move < scene.moves.size()) {
      const MoveEvent& mv = scene.moves[next_move];
      const uint64_t at = static_cast<uint64_t>(std::ceil(mv.time * fs));
      if (at > t) {
        if (at < t + frames) frames = static_cast<uint32_t>(at - t);
        break;
      }
      if (mv.object) {
        if (mv.position) position[*mv.object] = *mv.position;
        if (mv.orientation) orientation[*mv.object] = *mv.orientation;
      } else {
        if (mv.position) listener.position = *mv.position;
        if (mv.forward) listener.forward = *mv.forward;
        if (mv.up) listener.up = *mv.up;
      }
      moved = true;
      ++next_move;
    }
    if (moved) update_gains();
    // Events whose first sample falls in [t, t + frames): sample = ceil(time * fs).
    while (next < scene.events.size()) {
      const ImpactEvent& ev = scene.events[next];
      const uint64_t at = static_cast<uint64_t>(std::ceil(ev.time * fs));
      if (at >= t + frames) break;
      const ObjectModes& obj = objects[ev.object];
      if (synth.pending_excitations() + obj.modes.size() > synth.excitation_capacity()) {
        if (at > t) frames = static_cast<uint32_t>(at - t);  // render up to it, then excite
        break;
      }
      impact_coupling(obj, ev, amps);
      synth.strike(voices[ev.object], amps, ev.time * fs - static_cast<double>(t), ev.contact_time);
      ++next;
    }
    DriveInput drive;
    if (bank) {
      for (; next_shake < scene.shakes.size(); ++next_shake) {
        const ShakeEvent& ev = scene.shakes[next_shake];
        const uint64_t at = static_cast<uint64_t>(std::ceil(ev.time * fs));
        if (at >= t + frames) break;
        bank->shake(shakers.voice[next_shake], static_cast<float>(ev.energy),
                    static_cast<uint32_t>(at - t));
      }
      drive = bank->prepare(frames);
    }
    synth.render(frames, buf.data(), drive);
    if (bank) bank->finish(frames);
    rep.max_active_modes = std::max(rep.max_active_modes, synth.active_modes());
    audio.samples.insert(audio.samples.end(), buf.begin(), buf.begin() + frames * scene.channels);
    t += frames;
    if (options.progress && (t / block) % 256 == 0) options.progress(double(t) / double(limit));
    // Without a duration, stop once every event is played and everything has rung out.
    if (!scene.duration && next == scene.events.size() && next_move == scene.moves.size() &&
        next_shake == scene.shakes.size() && synth.active_modes() == 0 &&
        double(t) / fs >= last_event) {
      break;
    }
  }
  for (float x : audio.samples) rep.peak = std::max(rep.peak, double(std::abs(x)));
  rep.frames = audio.frames();
  rep.stats = synth.stats();
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (report) *report = rep;
  return audio;
}

}  // namespace chladni::runtime
