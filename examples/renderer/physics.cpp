#include "physics.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace {

constexpr double kStep = 1.0 / 240;

void check(chladni_status s, const char* what) {
  if (s != CHLADNI_OK) throw std::runtime_error(std::string(what) + ": " + chladni_last_error());
}

}  // namespace

Physics::Physics(chladni_runtime* rt) : rt_(rt) {
  world_.setGravity(btVector3(0, 0, -9.81f));
  floor_.setRestitution(0.4f);
  floor_.setFriction(0.6f);
  world_.addRigidBody(&floor_);
  // Five small solids (frequency Hz, decay 1/s, Pa at 1 m per N s), dropped one after another.
  const double freq[5][3] = {{812, 1960, 3720},
                             {1430, 2980, 5110},
                             {523, 1441, 2825},
                             {660, 1710, 3300},
                             {980, 2450, 4400}};
  const double decay[3] = {6, 10, 15}, amp[3] = {2.0, 1.2, 0.6};
  const btVector3 half[5] = {{0.06f, 0.06f, 0.01f},
                             {0.03f, 0.03f, 0.03f},
                             {0.12f, 0.01f, 0.01f},
                             {0.04f, 0.02f, 0.02f},
                             {0.05f, 0.05f, 0.02f}};
  const float colour[5][4] = {{0.9f, 0.6f, 0.2f, 1},
                              {0.3f, 0.7f, 0.9f, 1},
                              {0.8f, 0.8f, 0.3f, 1},
                              {0.6f, 0.9f, 0.5f, 1},
                              {0.9f, 0.4f, 0.6f, 1}};
  for (int k = 0; k < 5; ++k) {
    Body b;
    check(chladni_bank_from_modes(rt_, freq[k], decay, amp, 3, &b.bank), "chladni_bank_from_modes");
    b.release = 0.1 + 0.6 * k;
    b.shape = std::make_unique<btBoxShape>(half[k]);
    const btScalar mass = btScalar(7800.0 * 8 * half[k].x() * half[k].y() * half[k].z());
    btVector3 inertia;
    b.shape->calculateLocalInertia(mass, inertia);
    const btVector3 at(btScalar(-0.3 + 0.15 * k), 0, btScalar(0.45));
    const btQuaternion q(btVector3(1, 0.4f, 0.2f).normalized(), btScalar(0.3 + 0.4 * k));
    b.motion = std::make_unique<btDefaultMotionState>(btTransform(q, at));
    btRigidBody::btRigidBodyConstructionInfo info(mass, b.motion.get(), b.shape.get(), inertia);
    info.m_restitution = 0.45f;
    info.m_friction = 0.5f;
    b.rigid = std::make_unique<btRigidBody>(info);
    std::copy(colour[k], colour[k] + 4, b.rgba);
    bodies_.push_back(std::move(b));
  }
}

Physics::~Physics() {
  clear();
  world_.removeRigidBody(&floor_);
}

void Physics::clear() {
  for (std::size_t k = 0; k < released_; ++k) world_.removeRigidBody(bodies_[k].rigid.get());
  bodies_.clear();
  released_ = 0;
}

// A new contact strikes each body it touches, pushed away from the other, in its own frame.
void Physics::post(const btPersistentManifold* man, const btManifoldPoint& pt, double t,
                   FILE* log) {
  for (int side = 0; side < 2; ++side) {
    const btCollisionObject* o = side == 0 ? man->getBody0() : man->getBody1();
    const auto it = std::find_if(bodies_.begin(), bodies_.end(),
                                 [&](const Body& b) { return b.rigid.get() == o; });
    if (it == bodies_.end()) continue;
    const btVector3 n = side == 0 ? pt.m_normalWorldOnB : -pt.m_normalWorldOnB;
    const btVector3 dir = o->getWorldTransform().getBasis().transpose() * n;
    const btVector3 local = side == 0 ? pt.m_localPointA : pt.m_localPointB;
    chladni_impact im{};
    im.object = it->object;
    im.time = t;
    im.impulse = pt.getAppliedImpulse();
    im.direction[0] = dir.x(), im.direction[1] = dir.y(), im.direction[2] = dir.z();
    im.point[0] = local.x(), im.point[1] = local.y(), im.point[2] = local.z();
    im.vertex = -1;
    im.contact_time = 0.0005;
    check(chladni_impact_post(rt_, &im), "chladni_impact_post");
    const int body = int(it - bodies_.begin());
    impacts_.push_back({t, body, im.impulse});
    std::fprintf(log, "%.6f,%d,%.6g\n", t, body, im.impulse);
  }
}

void Physics::advance_to(double seconds, FILE* log) {
  while ((steps_ + 1) * kStep <= seconds) {
    ++steps_;
    const double t = chladni_runtime_time(rt_);  // the audio clock is the one sounds keep
    // Let go: into the world, and spawned in the runtime while it plays; the bank goes with its
    // last object.
    while (released_ < bodies_.size() && bodies_[released_].release <= steps_ * kStep) {
      Body& b = bodies_[released_++];
      const btTransform& tr = b.rigid->getWorldTransform();
      const btQuaternion q = tr.getRotation();
      const double pos[3] = {tr.getOrigin().x(), tr.getOrigin().y(), tr.getOrigin().z()},
                   ori[4] = {q.w(), q.x(), q.y(), q.z()};
      check(chladni_object_spawn(rt_, b.bank, pos, ori, 1.0, &b.object), "chladni_object_spawn");
      check(chladni_bank_release(rt_, b.bank), "chladni_bank_release");
      world_.addRigidBody(b.rigid.get());
    }
    world_.stepSimulation(btScalar(kStep), 0);
    for (std::size_t k = 0; k < released_; ++k) {
      const Body& b = bodies_[k];
      const btTransform& tr = b.rigid->getWorldTransform();
      const btVector3 p = tr.getOrigin();
      const btQuaternion q = tr.getRotation();
      const double pos[3] = {p.x(), p.y(), p.z()}, ori[4] = {q.w(), q.x(), q.y(), q.z()};
      check(chladni_object_move(rt_, b.object, t, pos, ori), "chladni_object_move");
    }
    for (int m = 0; m < dispatcher_.getNumManifolds(); ++m) {
      const btPersistentManifold* man = dispatcher_.getManifoldByIndexInternal(m);
      for (int c = 0; c < man->getNumContacts(); ++c) {
        const btManifoldPoint& pt = man->getContactPoint(c);
        if (pt.getLifeTime() == 1 && pt.getAppliedImpulse() >= 1e-3f) post(man, pt, t, log);
      }
    }
  }
}

std::vector<Rect> Physics::rects(int w, int h) const {
  // x in [-0.5, 0.5] m across, z in [-0.05, 0.7] m up.
  const auto sx = [&](double x) { return int((x + 0.5) * w); };
  const auto sz = [&](double z) { return int((0.7 - z) / 0.75 * h); };
  std::vector<Rect> out;
  out.push_back({0, sz(0), w, h - sz(0), {0.35f, 0.33f, 0.3f, 1}});
  for (const Body& b : bodies_) {
    btVector3 lo, hi;
    b.rigid->getAabb(lo, hi);
    Rect r{sx(lo.x()), sz(hi.z()), sx(hi.x()) - sx(lo.x()), sz(lo.z()) - sz(hi.z()), {}};
    std::copy(b.rgba, b.rgba + 4, r.rgba);
    out.push_back(r);
  }
  return out;
}
