// Objects and shakers (control thread), and the command queue's producer side (game thread).
#include <algorithm>
#include <cmath>
#include <numbers>

#include "chladni/runtime/scene/scene_objects.hpp"
#include "chladni/runtime/scene/scene_shakers.hpp"
#include "handles.hpp"

using namespace chladni;
using namespace chladni::runtime;
using chladni::capi::Command;
using chladni::capi::Kind;
using chladni::capi::live;
using chladni::capi::live_shaker;
using chladni::capi::post;

namespace chladni::capi {

void need_vector(const double* v, const char* what, bool nonzero) {
  if (!v) throw InputError(std::string(what) + " must not be null");
  // Beyond a billion metres, squared distances and pans stop being finite floats.
  for (int i = 0; i < 3; ++i)
    if (!(std::abs(v[i]) <= kMaxCoordinate))
      throw InputError(std::string(what) + " must be finite and within 1e9 m");
  if (nonzero && v[0] * v[0] + v[1] * v[1] + v[2] * v[2] == 0)
    throw InputError(std::string(what) + " must not be zero");
}

Quat unit_quaternion(const double* q) {
  if (!q) throw InputError("orientation must not be null");
  for (int i = 0; i < 4; ++i)
    if (!std::isfinite(q[i])) throw InputError("orientation must be finite (w, x, y, z)");
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 0)) throw InputError("orientation must not be zero");
  return {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
}

}  // namespace chladni::capi

// Takes back what the audio thread is done with: retired places (their bank loses an object,
// and is freed if released and now unused) and the storage installs swapped out.
void chladni_runtime::reclaim() {
  using capi::Return;
  auto vacate = [&](uint32_t k) {
    capi::Place& p = places[k];
    uint64_t expected = capi::handle_id(k, p.generation);
    p.id.compare_exchange_strong(expected, 0);  // a refused spawn was never removed
    if (p.bank && --p.bank->objects == 0 && p.bank->released) banks.erase(p.bank->id);
    p.bank = nullptr;
    free_places.push_back(k);
  };
  auto vacate_shaker = [&](uint32_t s) {
    capi::ShakerPlace& p = shakers[s];
    uint64_t expected = capi::handle_id(s, p.generation);
    p.id.compare_exchange_strong(expected, 0);  // gone with its object, or never placed
    free_shaker_places.push_back(s);
  };
  while (const Return* r = returns.front()) {
    const Return ret = *r;
    returns.pop();
    if (ret.kind == Return::Kind::Retired || ret.kind == Return::Kind::Refused) vacate(ret.place);
    if (ret.kind == Return::Kind::ShakerRetired) vacate_shaker(ret.place);
    if (ret.kind == Return::Kind::PaperRetired) reclaim_paper(ret.place);
    if (ret.kind == Return::Kind::ContactRetired) {
      capi::ContactPlace& p = contacts[ret.place];
      uint64_t expected = capi::handle_id(ret.place, p.generation);
      p.id.compare_exchange_strong(expected, 0);  // never placed
      free_contact_places.push_back(ret.place);
    }
    delete ret.prepared;
    delete ret.shaker;
    delete ret.contact;
  }
}

void chladni_runtime::check_time(double time) const {
  if (!std::isfinite(time)) throw InputError("time must be finite");
  const double now =
      static_cast<double>(clock.load(std::memory_order_acquire)) / config.sample_rate;
  if (time > now + config.horizon)
    throw InputError("time " + std::to_string(time) + " s is more than horizon (" +
                     std::to_string(config.horizon) + " s) ahead of the clock (" +
                     std::to_string(now) + " s)");
}

extern "C" {

chladni_status chladni_object_spawn(chladni_runtime* rt, chladni_bank bank,
                                    const double position[3], const double orientation[4],
                                    double gain, chladni_object* object) {
  return capi::guarded("chladni_object_spawn", [&] {
    if (!rt || !object) throw InputError("runtime and object must not be null");
    *object = chladni_object{0};
    rt->reclaim();
    capi::Bank& b = rt->bank(bank);
    capi::need_vector(position, "position", false);
    const Quat q = capi::unit_quaternion(orientation);
    if (!(gain >= 0 && gain <= capi::kMaxGain)) throw InputError("gain must be in [0, 1e6]");
    if (rt->free_places.empty()) {
      capi::fail(CHLADNI_QUEUE_FULL, "chladni_object_spawn: max_objects (" +
                                         std::to_string(rt->config.max_objects) +
                                         ") objects are alive or fading out");
      return CHLADNI_QUEUE_FULL;
    }
    std::unique_ptr<ScenePlayer::PreparedObject> prepared = rt->player->prepare_object(
        b.modes, b.table.get(), {position[0], position[1], position[2]}, q, gain);
    const uint32_t k = rt->free_places.back();
    capi::Place& p = rt->places[k];
    const uint32_t generation = capi::next_generation(p.generation);
    const uint64_t id = capi::handle_id(k, generation);
    capi::Change ch{capi::Change::Kind::Spawn, k, id};
    ch.prepared = prepared.get();
    if (!rt->changes.push(ch))
      throw InternalError("the change queue is full");  // sized for every place: a bug
    prepared.release();  // the audio thread hands it back through `returns`
    rt->free_places.pop_back();
    p.generation = generation;
    ++b.objects;
    p.bank = &b;
    p.points.store(b.model && b.model->has_geometry() ? b.model->points.size() : 0,
                   std::memory_order_relaxed);
    p.id.store(id, std::memory_order_release);
    *object = chladni_object{id};
    return CHLADNI_OK;
  });
}

chladni_status chladni_object_remove(chladni_runtime* rt, chladni_object object) {
  return capi::guarded("chladni_object_remove", [&] {
    if (!rt) throw InputError("runtime must not be null");
    rt->reclaim();
    const uint32_t k = live(rt, object);
    if (!rt->changes.push({capi::Change::Kind::Remove, k, object.id}))
      throw InternalError("the change queue is full");
    rt->places[k].id.store(0, std::memory_order_release);  // commands are refused from now on
    return CHLADNI_OK;
  });
}

chladni_status chladni_shaker_add(chladni_runtime* rt, const chladni_shaker_desc* desc,
                                  chladni_shaker* shaker) {
  return capi::guarded("chladni_shaker_add", [&] {
    if (!rt || !desc || !shaker || !desc->instrument)
      throw InputError("runtime, desc, desc->instrument and shaker must not be null");
    *shaker = chladni_shaker{0};
    rt->reclaim();
    const uint32_t k = live(rt, desc->object);
    if (rt->config.shaker_slots == 0)
      throw InputError("the runtime was created with shaker_slots = 0: no room for shakers");
    if (!(desc->particles >= 0 && desc->particles <= 1e6))
      throw InputError("particles must be in [0, 1e6]");
    if (!(desc->impulse >= 0 && desc->impulse <= 1e3))
      throw InputError("impulse must be in [0, 1e3] N s");
    if (rt->free_shaker_places.empty()) {
      capi::fail(CHLADNI_QUEUE_FULL, "chladni_shaker_add: max_shakers (" +
                                         std::to_string(rt->config.max_shakers) +
                                         ") shakers are alive or fading out");
      return CHLADNI_QUEUE_FULL;
    }
    const uint32_t s = rt->free_shaker_places.back();
    ShakeEvent ev;
    ev.json_path = "shaker";
    ev.object = k;
    ev.instrument = desc->instrument;
    ev.particles = desc->particles;
    ev.resonate_object = desc->resonate_object != 0;
    if (desc->impulse > 0) ev.impulse = desc->impulse;
    // Seeded by place, as the offline player seeds its k-th shaker.
    const ShakerVoice voice =
        shake_voice(ev, rt->places[k].bank->modes, rt->config.sample_rate, 1 + s);
    std::unique_ptr<ScenePlayer::PreparedShaker> prepared =
        rt->player->prepare_shaker(voice, ev.resonate_object);
    capi::ShakerPlace& p = rt->shakers[s];
    const uint32_t generation = capi::next_generation(p.generation);
    const uint64_t id = capi::handle_id(s, generation);
    capi::Change ch{capi::Change::Kind::AddShaker, s, id};
    ch.object = desc->object.id;
    ch.shaker = prepared.get();
    if (!rt->changes.push(ch)) throw InternalError("the change queue is full");
    prepared.release();  // the audio thread hands it back through `returns`
    rt->free_shaker_places.pop_back();
    p.generation = generation;
    p.object.store(desc->object.id, std::memory_order_relaxed);
    p.id.store(id, std::memory_order_release);
    *shaker = chladni_shaker{id};
    return CHLADNI_OK;
  });
}

chladni_status chladni_shaker_remove(chladni_runtime* rt, chladni_shaker shaker) {
  return capi::guarded("chladni_shaker_remove", [&] {
    if (!rt) throw InputError("runtime must not be null");
    rt->reclaim();
    const uint32_t s = live_shaker(rt, shaker);
    if (!rt->changes.push({capi::Change::Kind::RemoveShaker, s, shaker.id}))
      throw InternalError("the change queue is full");
    rt->shakers[s].id.store(0, std::memory_order_release);  // shakes are refused from now on
    return CHLADNI_OK;
  });
}

chladni_status chladni_shaker_shake(chladni_runtime* rt, chladni_shaker shaker, double time,
                                    double energy) {
  return capi::guarded("chladni_shaker_shake", [&] {
    if (!rt) throw InputError("runtime must not be null");
    const uint32_t s = live_shaker(rt, shaker);
    const chladni_object object{rt->shakers[s].object.load(std::memory_order_relaxed)};
    live(rt, object);
    rt->check_time(time);
    if (!(energy > 0 && energy <= 1)) throw InputError("energy must be in (0, 1]");
    Command c{};
    c.kind = Kind::Shake;
    c.object = object.id;
    c.shaker = shaker.id;
    c.time = time;
    c.impulse = energy;
    return post(rt, c);
  });
}

chladni_status chladni_impact_post(chladni_runtime* rt, const chladni_impact* im) {
  return capi::guarded("chladni_impact_post", [&] {
    if (!rt || !im) throw InputError("runtime and impact must not be null");
    const uint32_t k = live(rt, im->object);
    rt->check_time(im->time);
    if (!(im->impulse > 0 && im->impulse <= capi::kMaxImpulse))
      throw InputError("impulse must be in (0, 1e6] N s");
    if (!(im->contact_time >= 0 && im->contact_time <= 0.1))
      throw InputError("contact_time must be in [0, 0.1] s");
    capi::need_vector(im->direction, "direction");
    Command c{};
    c.kind = Kind::Impact;
    c.object = im->object.id;
    c.time = im->time;
    c.impulse = im->impulse;
    c.contact = im->contact_time;
    c.vertex = im->vertex;
    const double n =
        std::sqrt(im->direction[0] * im->direction[0] + im->direction[1] * im->direction[1] +
                  im->direction[2] * im->direction[2]);
    for (int i = 0; i < 3; ++i) c.a[i] = im->direction[i] / n;
    if (im->vertex >= 0) {
      const uint64_t points = rt->places[k].points.load(std::memory_order_relaxed);
      if (static_cast<uint64_t>(im->vertex) >= points)
        throw InputError("vertex " + std::to_string(im->vertex) + " is out of range (the object " +
                         "has " + std::to_string(points) + " surface points)");
    } else {
      capi::need_vector(im->point, "point", false);
      for (int i = 0; i < 3; ++i) c.b[i] = im->point[i];
    }
    return post(rt, c);
  });
}

chladni_status chladni_object_move(chladni_runtime* rt, chladni_object object, double time,
                                   const double position[3], const double orientation[4]) {
  return capi::guarded("chladni_object_move", [&] {
    if (!rt) throw InputError("runtime must not be null");
    live(rt, object);
    rt->check_time(time);
    capi::need_vector(position, "position", false);
    const Quat q = capi::unit_quaternion(orientation);
    Command c{};
    c.kind = Kind::Move;
    c.object = object.id;
    c.time = time;
    for (int i = 0; i < 3; ++i) c.a[i] = position[i];
    for (int i = 0; i < 4; ++i) c.q[i] = q[i];
    return post(rt, c);
  });
}

chladni_status chladni_listener_set(chladni_runtime* rt, double time, const double position[3],
                                    const double forward[3], const double up[3]) {
  return capi::guarded("chladni_listener_set", [&] {
    if (!rt) throw InputError("runtime must not be null");
    rt->check_time(time);
    capi::need_vector(position, "position", false);
    capi::need_vector(forward, "forward");
    capi::need_vector(up, "up");
    Vec3 f{forward[0], forward[1], forward[2]}, u{up[0], up[1], up[2]};
    const Vec3 side = cross(f, u);
    if (dot(side, side) < 1e-18 * dot(f, f) * dot(u, u))
      throw InputError("forward and up must not be parallel");
    Command c{};
    c.kind = Kind::Listener;
    c.time = time;
    const double fn = std::sqrt(dot(f, f)), un = std::sqrt(dot(u, u));
    for (int i = 0; i < 3; ++i) {
      c.a[i] = position[i];
      c.b[i] = f[i] / fn;
      c.c[i] = u[i] / un;
    }
    const chladni_status s = post(rt, c);
    if (s == CHLADNI_OK) {  // a sequence lock: the paper sheets' reader retries a torn read
      const uint64_t seq = rt->listener_seq.load(std::memory_order_relaxed);
      rt->listener_seq.store(seq + 1, std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_release);
      for (int i = 0; i < 3; ++i) {
        rt->listener[i].store(c.a[i], std::memory_order_relaxed);
        rt->listener[3 + i].store(c.b[i], std::memory_order_relaxed);
        rt->listener[6 + i].store(c.c[i], std::memory_order_relaxed);
      }
      rt->listener_seq.store(seq + 2, std::memory_order_release);
    }
    return s;
  });
}

}  // extern "C"
