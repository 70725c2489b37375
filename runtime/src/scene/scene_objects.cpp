#include "chladni/runtime/scene/scene_objects.hpp"

#include <cstdio>
#include <numbers>

#include "chladni/core/analytic_bar.hpp"
#include "chladni/core/error.hpp"
#include "chladni/runtime/modal/transfer_gains.hpp"

namespace chladni::runtime {
namespace {

std::string lowest(const ModalModel& model) {
  std::string s = "; lowest";
  char buf[32];
  for (std::size_t i = 0; i < std::min<std::size_t>(5, model.mode_count()); ++i) {
    std::snprintf(buf, sizeof buf, " %.1f", model.damped_omega(i) / (2 * std::numbers::pi));
    s += buf;
  }
  return s + " Hz";
}

PlayableObject bar_object(const SceneObject& obj, double fs) {
  PlayableObject p;
  try {
    p.model = std::make_unique<ModalModel>(analytic_bar(obj.bar));
  } catch (const InputError& e) {
    throw InputError(obj.json_path + ".bar: " + e.what());
  }
  p.model->name = obj.name;
  const ModeSelection sel =
      apply_damping(*p.model, obj.bar.damping, 20.0, obj.bar.max_frequency, fs);
  keep_modes(*p.model, sel.kept);
  if (p.model->mode_count() == 0)
    throw InputError(obj.json_path + ".bar: no mode lies in the audible band");
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "analytic bar %.3f x %.3f x %.3f m, %s: %zu modes (%zu overdamped, %zu out of "
                "band)",
                obj.bar.length, obj.bar.width, obj.bar.thickness,
                obj.bar.damping.to_string().c_str(), p.model->mode_count(), sel.overdamped,
                sel.below_band + sel.above_band);
  p.summary = buf + lowest(*p.model);
  return p;
}

}  // namespace

ModalModel playable_model(const Soundbank& bank, const std::string& name, double sample_rate,
                          const std::string& what, std::size_t* dropped) {
  ModalModel model = to_modal_model(bank, name);
  // The bank was made for some sample rate; keep what this one can play.
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < model.mode_count(); ++i)
    if (model.damped_omega(i) < std::numbers::pi * sample_rate) kept.push_back(i);
  if (dropped) *dropped = model.mode_count() - kept.size();
  keep_modes(model, kept);
  if (model.mode_count() == 0) {
    char rate[32];
    std::snprintf(rate, sizeof rate, "%g", sample_rate);
    throw InputError(what + " has no mode below the Nyquist frequency at " + rate + " Hz");
  }
  return model;
}

PlayableObject resolve_object(const SceneObject& obj, double fs) {
  PlayableObject p;
  switch (obj.source) {
    case SceneObject::Source::Modes:
      p.modes = object_modes(obj.modes);
      p.summary = std::to_string(obj.modes.size()) + " inline modes";
      return p;
    case SceneObject::Source::Bar:
      p = bar_object(obj, fs);
      break;
    case SceneObject::Source::Soundbank: {
      const Soundbank bank = read_soundbank(obj.soundbank);
      std::size_t dropped = 0;
      p.model = std::make_unique<ModalModel>(playable_model(
          bank, obj.name, fs, obj.json_path + ".soundbank: " + obj.soundbank, &dropped));
      p.summary = "soundbank " + obj.soundbank + " (" + bank.material.name + ", " +
                  bank.material.damping.to_string() +
                  "): " + std::to_string(p.model->mode_count()) + " modes (" +
                  std::to_string(dropped) + " above Nyquist)" + lowest(*p.model);
      break;
    }
  }
  p.modes = object_modes(*p.model);
  return p;
}

std::vector<PlayableObject> resolve_objects(const Scene& scene) {
  std::vector<PlayableObject> out;
  for (const SceneObject& obj : scene.objects)
    out.push_back(resolve_object(obj, scene.sample_rate));
  return out;
}

void listener_mode_gains(const ObjectModes& object, std::span<const float> transfer, double scale,
                         double spread, std::span<float> out) {
  const bool xfer = !transfer.empty() && object.transfer;
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = xfer && object.transfer->usable(i) ? static_cast<float>(scale * transfer[i])
                                                : static_cast<float>(object.modes[i].gain * spread);
  }
}

void gains_at_listener(const ModalModel& model, ObjectModes& object, const Vec3& listener) {
  std::vector<float> xfer;
  if (model.transfer) {
    TransferTable table;
    table.map_options.reset();  // one update: the series costs less than building maps
    table.add(*model.transfer);
    ListenerFrame frame;
    const Vec3 at[1] = {listener};
    frame.update(table, at);
    xfer.resize(table.mode_count());
    transfer_gains(table, frame, xfer);
  }
  std::vector<float> gains(object.modes.size());
  listener_mode_gains(object, xfer, 1.0, 1.0 / std::max(norm(listener), 0.1), gains);
  for (std::size_t i = 0; i < gains.size(); ++i) object.modes[i].gain = gains[i];
}

}  // namespace chladni::runtime
