// ScenePlayer's continuous contacts: their bank, gains and input rows beside the shakers'.
#include <cstring>

#include "chladni/core/error.hpp"
#include "chladni/runtime/scene/scene_player.hpp"

namespace chladni::runtime {

std::unique_ptr<ContactBank::Prepared> ScenePlayer::prepare_contact(const ObjectModes& body,
                                                                    const ObjectModes* other,
                                                                    const Roughness& roughness,
                                                                    uint64_t seed,
                                                                    const std::string& name) const {
  if (!contacts_) throw InputError(name + ": the player has no room for contacts");
  ContactSpec spec;
  spec.name = name;
  spec.roughness = roughness;
  spec.seed = seed;
  spec.bodies = {&body, other};
  return contacts_->prepare(spec);
}

bool ScenePlayer::install_contact(int index, std::size_t object, long other,
                                  ContactBank::Prepared& prepared) noexcept {
  if (!contacts_ || index < 0 || std::size_t(index) >= contact_objects_.size()) return false;
  auto live = [&](long k) {
    return k >= 0 && std::size_t(k) < objects_.size() && objects_[k].voice >= 0;
  };
  if (!live(long(object)) || (other >= 0 && !live(other))) return false;
  if (!contacts_->install(prepared, uint32_t(index))) return false;
  contact_objects_[index] = {long(object), other};
  dirty_ = true;  // its modes take the objects' gains at the next update
  return true;
}

int ScenePlayer::add_contact(std::size_t object, long other, const Roughness& roughness,
                             uint64_t seed, const std::string& name) {
  const long ids[2] = {long(object), other};
  for (long id : ids)
    if (id >= 0 && (std::size_t(id) >= objects_.size() || objects_[id].voice < 0))
      throw InputError(name + ": object " + std::to_string(id) + " is not in the scene");
  auto p = prepare_contact(objects_[object].modes, other >= 0 ? &objects_[other].modes : nullptr,
                           roughness, seed, name);
  const int k = int(contacts_->contact_count());
  if (!install_contact(k, object, other, *p))
    throw InputError(name + ": the player has no room for it");
  return k;
}

void ScenePlayer::remove_contact(int contact) {
  if (!contacts_ || !contacts_->live(contact)) return;
  // Its objects stay until it is freed: their removal silences its ring-down too.
  contacts_->remove(contact, synth_.time());
}

// An object removed ends the contacts that touch it, and its side of them fades out with it.
void ScenePlayer::end_contacts_of(std::size_t object) {
  const Object& o = objects_[object];
  for (std::size_t k = 0; k < contact_objects_.size(); ++k) {
    for (int b = 0; b < 2; ++b) {
      if (contact_objects_[k][b] != long(object)) continue;
      contacts_->end(int(k), synth_.time());
      contacts_->set_gains(int(k), b, o.gains, 0.0f, 0.0f);
      contact_objects_[k][b] = -1;
    }
  }
}

bool ScenePlayer::push_contact(int contact, const ContactPoint& point) {
  return contacts_ && contacts_->push(contact, point);
}

void ScenePlayer::end_contact(int contact, uint64_t sample) {
  if (contacts_) contacts_->end(contact, sample);
}

void ScenePlayer::apply_contact_gains() {
  for (std::size_t k = 0; k < contact_objects_.size(); ++k) {
    if (!contacts_->live(int(k))) continue;
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
  contacts_->render(synth_.time(), frames, drive_.data());
  for (uint32_t k : contacts_->retired()) contact_objects_[k] = {-1, -1};
  return in;
}

}  // namespace chladni::runtime
