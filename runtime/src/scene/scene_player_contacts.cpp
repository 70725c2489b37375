// ScenePlayer's continuous contacts: their bank, gains and input rows beside the shakers'.
#include <cstring>

#include "chladni/core/error.hpp"
#include "chladni/runtime/scene/scene_player.hpp"

namespace chladni::runtime {

int ScenePlayer::add_contact(std::size_t object, long other, const Roughness& roughness,
                             uint64_t seed, const std::string& name) {
  if (!contacts_) throw InputError(name + ": the player has no room for contacts");
  ContactSpec spec;
  spec.name = name;
  spec.roughness = roughness;
  spec.seed = seed;
  const long ids[2] = {long(object), other};
  for (int b = 0; b < 2; ++b) {
    if (ids[b] < 0) continue;
    if (std::size_t(ids[b]) >= objects_.size() || objects_[ids[b]].voice < 0)
      throw InputError(name + ": object " + std::to_string(ids[b]) + " is not in the scene");
    spec.bodies[b] = &objects_[ids[b]].modes;
  }
  const int k = contacts_->add_contact(spec);
  contact_objects_.push_back({ids[0], ids[1]});
  dirty_ = true;  // its modes take the objects' gains at the next update
  return k;
}

bool ScenePlayer::push_contact(int contact, const ContactPoint& point) {
  return contacts_ && contacts_->push(contact, point);
}

void ScenePlayer::end_contact(int contact, uint64_t sample) {
  if (contacts_) contacts_->end(contact, sample);
}

void ScenePlayer::apply_contact_gains() {
  for (std::size_t k = 0; k < contact_objects_.size(); ++k) {
    for (int b = 0; b < 2; ++b) {
      const long id = contact_objects_[k][b];
      if (id < 0) continue;
      const Object& o = objects_[id];
      const bool live = o.voice >= 0;
      contacts_->set_gains(int(k), b, o.gains, live ? o.pan[0] : 0.0f, live ? o.pan[1] : 0.0f);
    }
  }
}

// The input of the next block: the shakers' rows (made on the host, or by the device stage)
// followed by the contacts'.
DriveInput ScenePlayer::drive(uint32_t frames) {
  const DriveInput shakers = bank_ ? bank_->prepare(frames) : DriveInput{};
  if (!contacts_ || contacts_->contact_count() == 0) return shakers;
  DriveInput in{drive_.data(), contacts_->streams()};
  if (shakers.streams > 0 && shakers.samples)
    std::memcpy(drive_.data(), shakers.samples, sizeof(float) * shakers.streams * frames);
  else if (shakers.streams > 0)
    in.device_rows = shakers.streams;
  contacts_->prepare(synth_.time(), frames, drive_.data());
  return in;
}

}  // namespace chladni::runtime
