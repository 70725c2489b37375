// Continuous contacts through the C API: added on the control thread, their states posted from
// the game thread, pushed into the player's contact bank on the audio thread.
#include <algorithm>
#include <cmath>

#include "chladni/runtime/scene/scene_contacts.hpp"
#include "handles.hpp"

using namespace chladni;
using namespace chladni::runtime;
using chladni::capi::Command;
using chladni::capi::Kind;

namespace {

constexpr double kMaxForce = 1e6, kMaxSpeed = 100;
// A posted point may lie this far outside its body's box, as a share of the box's diagonal
// (docs/contact.md: a point on a face lies up to half an edge from the surface samples).
constexpr double kOffBox = 0.1;

uint32_t live_contact(const chladni_runtime* rt, chladni_contact contact) {
  return capi::live_place(contact.id, rt->contacts.get(), rt->max_contacts(), "contact",
                          "never added, or removed");
}

// The box a body's posted points must lie in: its surface points' grown by a tenth of its
// diagonal; everything for a body without geometry.
void body_box(const capi::Bank& b, std::atomic<double>* out) {
  double box[6] = {-INFINITY, -INFINITY, -INFINITY, INFINITY, INFINITY, INFINITY};
  if (b.model && b.model->has_geometry()) {
    const auto [lo, hi] = b.model->surface_box();
    for (int k = 0; k < 3; ++k) box[k] = lo[k], box[3 + k] = hi[k];
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += (box[3 + k] - box[k]) * (box[3 + k] - box[k]);
    const double grow = kOffBox * std::sqrt(d2);
    for (int k = 0; k < 3; ++k) box[k] -= grow, box[3 + k] += grow;
  }
  for (int k = 0; k < 6; ++k) out[k].store(box[k], std::memory_order_relaxed);
}

void need_in_box(const double* p, const std::atomic<double>* box, const char* what) {
  capi::need_vector(p, what, false);
  for (int k = 0; k < 3; ++k)
    if (p[k] < box[k].load(std::memory_order_relaxed) ||
        p[k] > box[3 + k].load(std::memory_order_relaxed))
      throw InputError(std::string(what) + " (" + std::to_string(p[0]) + ", " +
                       std::to_string(p[1]) + ", " + std::to_string(p[2]) +
                       ") lies off its body: farther from its surface's box than a tenth of the "
                       "box's size");
}

void need_in(double x, double max, const char* what) {
  if (!(x >= 0 && x <= max))
    throw InputError(std::string(what) + " must be in [0, " + std::to_string(max) + "]");
}

}  // namespace

// The audio thread: every queued state of a contact installed here goes into its bank's queue
// at once, in time order (the bank interpolates towards the states ahead of the block).
void chladni_runtime::apply_contacts(uint64_t t) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < pending.size(); ++i) {
    const Command& c = pending[i];
    if (c.kind != Kind::Contact) {
      pending[kept++] = c;
      continue;
    }
    const uint32_t k = capi::place_of(c.shaker);
    if (k >= installed_contact_ids.size() || installed_contact_ids[k] != c.shaker) continue;
    const uint64_t objects[2] = {c.object, c.other};
    ContactPoint p;
    p.sample = std::max(t, sample_of(c));
    p.force = float(c.impulse);
    p.slip = float(c.contact);
    p.rolling = float(c.c[0]);
    bool bodies = true;
    for (int b = 0; b < 2 && bodies; ++b) {
      if (objects[b] == 0) continue;
      bodies = installed(objects[b]);
      const ObjectModes& m = player->modes(capi::place_of(objects[b]));
      const double* q = b == 0 ? c.a : c.b;
      if (bodies && m.model && m.model->has_geometry())
        p.vertex[b] = uint32_t(m.model->nearest_point({q[0], q[1], q[2]}));
    }
    if (!bodies || !player->push_contact(int(k), p)) ++dropped_commands;
  }
  pending.resize(kept);
}

extern "C" {

chladni_status chladni_contact_add(chladni_runtime* rt, const chladni_contact_desc* desc,
                                   chladni_contact* contact) {
  return capi::guarded("chladni_contact_add", [&] {
    if (!rt || !desc || !contact) throw InputError("runtime, desc and contact must not be null");
    *contact = chladni_contact{0};
    rt->reclaim();
    const uint32_t k = capi::live(rt, desc->object);
    const long other = desc->other.id ? long(capi::live(rt, desc->other)) : -1;
    if (other == long(k)) throw InputError("other must be another object");
    if (rt->config.contact_slots == 0)
      throw InputError("the runtime was created with contact_slots = 0: no room for contacts");
    if (!(desc->level >= 0 && desc->level <= 10)) throw InputError("level must be in [0, 10]");
    RoughnessSpec spec;
    if (desc->surface) spec.surface = desc->surface;
    if (desc->level > 0) spec.level = desc->level;
    if (!(desc->ribs >= 0 && desc->rib_depth >= 0))  // NaN too
      throw InputError("ribs and rib_depth must be >= 0");
    if (desc->ribs > 0) spec.ribs = desc->ribs;
    if (desc->rib_depth > 0) spec.rib_depth = desc->rib_depth;
    const Roughness roughness = resolve_roughness(spec);
    if (rt->free_contact_places.empty()) {
      capi::fail(CHLADNI_QUEUE_FULL, "chladni_contact_add: max_contacts (" +
                                         std::to_string(rt->config.max_contacts) +
                                         ") contacts are alive or ringing down");
      return CHLADNI_QUEUE_FULL;
    }
    const uint32_t s = rt->free_contact_places.back();
    const capi::Bank& a = *rt->places[k].bank;
    const capi::Bank* b = other >= 0 ? rt->places[other].bank : nullptr;
    std::unique_ptr<ContactBank::Prepared> prepared = rt->player->prepare_contact(
        a.modes, b ? &b->modes : nullptr, roughness, desc->seed ? desc->seed : 1, "contact");
    capi::ContactPlace& p = rt->contacts[s];
    body_box(a, p.box[0]);
    if (b) body_box(*b, p.box[1]);
    const uint32_t generation = capi::next_generation(p.generation);
    const uint64_t id = capi::handle_id(s, generation);
    capi::Change ch{capi::Change::Kind::AddContact, s, id};
    ch.object = desc->object.id;
    ch.other = desc->other.id;
    ch.contact = prepared.get();
    if (!rt->changes.push(ch)) throw InternalError("the change queue is full");
    prepared.release();  // the audio thread hands it back through `returns`
    rt->free_contact_places.pop_back();
    p.generation = generation;
    p.object.store(desc->object.id, std::memory_order_relaxed);
    p.other.store(desc->other.id, std::memory_order_relaxed);
    p.id.store(id, std::memory_order_release);
    *contact = chladni_contact{id};
    return CHLADNI_OK;
  });
}

chladni_status chladni_contact_post(chladni_runtime* rt, chladni_contact contact,
                                    const chladni_contact_state* st) {
  return capi::guarded("chladni_contact_post", [&] {
    if (!rt || !st) throw InputError("runtime and state must not be null");
    const uint32_t s = live_contact(rt, contact);
    const capi::ContactPlace& p = rt->contacts[s];
    const chladni_object object{p.object.load(std::memory_order_relaxed)};
    const chladni_object other{p.other.load(std::memory_order_relaxed)};
    capi::live(rt, object);
    if (other.id) capi::live(rt, other);
    rt->check_time(st->time);
    need_in(st->normal_force, kMaxForce, "normal_force (N)");
    need_in(st->slip_speed, kMaxSpeed, "slip_speed (m/s)");
    need_in(st->rolling_speed, kMaxSpeed, "rolling_speed (m/s)");
    need_in_box(st->point, p.box[0], "point");
    if (other.id) need_in_box(st->other_point, p.box[1], "other_point");
    Command c{};
    c.kind = Kind::Contact;
    c.object = object.id;
    c.other = other.id;
    c.shaker = contact.id;
    c.time = st->time;
    c.impulse = st->normal_force;
    c.contact = st->slip_speed;
    c.c[0] = st->rolling_speed;
    std::copy(st->point, st->point + 3, c.a);
    if (other.id) std::copy(st->other_point, st->other_point + 3, c.b);
    return capi::post(rt, c);
  });
}

chladni_status chladni_contact_remove(chladni_runtime* rt, chladni_contact contact) {
  return capi::guarded("chladni_contact_remove", [&] {
    if (!rt) throw InputError("runtime must not be null");
    rt->reclaim();
    const uint32_t s = live_contact(rt, contact);
    if (!rt->changes.push({capi::Change::Kind::RemoveContact, s, contact.id}))
      throw InternalError("the change queue is full");
    rt->contacts[s].id.store(0, std::memory_order_release);  // posts are refused from now on
    return CHLADNI_OK;
  });
}

}  // extern "C"
