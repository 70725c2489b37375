// Falling objects: Bullet drops sounding objects onto a floor and into each other; every new
// contact becomes an impact through Chladni's C API, posted at the physics step's time; a body
// sliding on a contact scrapes (a shaker of sandpaper grains ringing its modes, shaken in
// proportion to the sliding speed); the audio is rendered in step with the simulation (200
// frames per 1/240 s step at 48 kHz).
// Writes a stereo float WAV (normalized to -1 dBFS; the peak in pascals is printed) and a
// frame-by-frame event log (CSV), and prints when the first impact happened and when the first
// sound starts.
//
// Usage: falling_objects [BANK.chbank ...] [--seconds S] [--no-scrape] [-o OUT.wav]
//                        [--log EVENTS.csv]
// Without banks, three bodies sound with inline modes (a tile, a block, a rod).
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "chladni/chladni.h"

namespace {

constexpr double kRate = 48000, kStep = 1.0 / 240;
constexpr uint32_t kFramesPerStep = 200;
// Sliding slower than this is resting; at kFullSlip the grains get all the energy a shake adds.
constexpr double kMinSlip = 0.02, kFullSlip = 1.0;  // m/s

void check(chladni_status s, const char* what) {
  if (s != CHLADNI_OK) throw std::runtime_error(std::string(what) + ": " + chladni_last_error());
}

struct Body {
  chladni_object object{0};
  chladni_shaker scrape{0};  // its shaker: grains on its surface
  double slip = 0;           // this step's fastest sliding contact (m/s)
  btVector3 centre;          // the box's centre in the bank's frame: the body's origin
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btDefaultMotionState> motion;
  std::unique_ptr<btRigidBody> rigid;
};

// A sounding body: a box the size of its bank's surface (or `half` for inline modes).
Body make_body(chladni_runtime* rt, chladni_bank bank, btVector3 half, const btVector3& at,
               const btQuaternion& q) {
  Body b;
  double lo[3], hi[3];
  b.centre = btVector3(0, 0, 0);
  if (chladni_bank_bounds(rt, bank, lo, hi) == CHLADNI_OK) {
    half = btVector3(btScalar(hi[0] - lo[0]), btScalar(hi[1] - lo[1]), btScalar(hi[2] - lo[2])) / 2;
    b.centre =
        btVector3(btScalar(hi[0] + lo[0]), btScalar(hi[1] + lo[1]), btScalar(hi[2] + lo[2])) / 2;
  }
  for (int c = 0; c < 3; ++c) half[c] = std::max(half[c], btScalar(0.003));
  b.shape = std::make_unique<btBoxShape>(half);
  // The solid's own mass where the bank knows it (a bowl weighs far less than its box of metal).
  const double solid = chladni_bank_mass(rt, bank);
  const btScalar mass = btScalar(solid > 0 ? solid : 7800.0 * 8 * half.x() * half.y() * half.z());
  btVector3 inertia;
  b.shape->calculateLocalInertia(mass, inertia);
  b.motion = std::make_unique<btDefaultMotionState>(btTransform(q, at));
  btRigidBody::btRigidBodyConstructionInfo info(mass, b.motion.get(), b.shape.get(), inertia);
  info.m_restitution = 0.4f;
  info.m_friction = 0.5f;
  b.rigid = std::make_unique<btRigidBody>(info);
  const double pos[3] = {at.x(), at.y(), at.z()}, ori[4] = {q.w(), q.x(), q.y(), q.z()};
  check(chladni_object_spawn(rt, bank, pos, ori, 1.0, &b.object), "spawn");
  chladni_shaker_desc grains{};
  grains.object = b.object;
  grains.instrument = "sandpaper";
  grains.resonate_object = 1;
  grains.impulse = 5e-5;  // N s per grain: sliding stays below the impacts that start it
  check(chladni_shaker_add(rt, &grains, &b.scrape), "shaker");
  return b;
}

// The object's pose for the runtime: its bank's frame, whose origin sits `centre` away from the
// body's.
void post_pose(chladni_runtime* rt, const Body& b, double time) {
  const btTransform& t = b.rigid->getWorldTransform();
  const btVector3 origin = t.getOrigin() - t.getBasis() * b.centre;
  const btQuaternion q = t.getRotation();
  const double pos[3] = {origin.x(), origin.y(), origin.z()}, ori[4] = {q.w(), q.x(), q.y(), q.z()};
  check(chladni_object_move(rt, b.object, time, pos, ori), "move");
}

// Speed of `o`'s surface at world point `p`.
btVector3 surface_velocity(const btCollisionObject* o, const btVector3& p) {
  const btRigidBody* rb = btRigidBody::upcast(o);
  if (!rb) return btVector3(0, 0, 0);
  return rb->getLinearVelocity() +
         rb->getAngularVelocity().cross(p - rb->getCenterOfMassPosition());
}

void write_wav(const std::string& path, const std::vector<float>& samples, int channels) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path);
  const uint32_t data = static_cast<uint32_t>(samples.size() * sizeof(float));
  const uint32_t rate = static_cast<uint32_t>(kRate), bytes_per_s = rate * channels * 4;
  const uint16_t fmt = 3, ch = static_cast<uint16_t>(channels), align = ch * 4, bits = 32;
  const uint32_t riff = 36 + data, fmt_size = 16;
  std::fwrite("RIFF", 1, 4, f), std::fwrite(&riff, 4, 1, f), std::fwrite("WAVEfmt ", 1, 8, f);
  std::fwrite(&fmt_size, 4, 1, f), std::fwrite(&fmt, 2, 1, f), std::fwrite(&ch, 2, 1, f);
  std::fwrite(&rate, 4, 1, f), std::fwrite(&bytes_per_s, 4, 1, f), std::fwrite(&align, 2, 1, f);
  std::fwrite(&bits, 2, 1, f), std::fwrite("data", 1, 4, f), std::fwrite(&data, 4, 1, f);
  std::fwrite(samples.data(), sizeof(float), samples.size(), f);
  if (std::fclose(f) != 0) throw std::runtime_error("cannot write " + path);
}

struct Options {
  std::vector<std::string> banks;
  double seconds = 3;
  bool scrape = true;
  std::string wav = "falling_objects.wav", log_path = "falling_objects.csv";
};

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seconds" && i + 1 < argc)
      o.seconds = std::stod(argv[++i]);
    else if (a == "--no-scrape")
      o.scrape = false;
    else if (a == "-o" && i + 1 < argc)
      o.wav = argv[++i];
    else if (a == "--log" && i + 1 < argc)
      o.log_path = argv[++i];
    else
      o.banks.push_back(a);
  }
  if (!(o.seconds > 0 && o.seconds <= 600))
    throw std::runtime_error("--seconds must be in (0, 600]");
  return o;
}

// The Bullet world: z up, a floor at z = 0.
struct World {
  btDefaultCollisionConfiguration collision;
  btCollisionDispatcher dispatcher{&collision};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &collision};
  btStaticPlaneShape floor_shape{btVector3(0, 0, 1), 0};
  btDefaultMotionState floor_motion;
  btRigidBody floor{btRigidBody::btRigidBodyConstructionInfo(0, &floor_motion, &floor_shape)};

  World() {
    world.setGravity(btVector3(0, 0, -9.81f));
    floor.setRestitution(0.4f);
    floor.setFriction(0.6f);
    world.addRigidBody(&floor);
  }
  ~World() { world.removeRigidBody(&floor); }
};

// The banks named, or three with inline modes (frequency Hz, decay 1/s, Pa at 1 m per N s), as
// bodies stacked loosely above one another, tilted, so they hit the floor and each other.
std::vector<Body> make_bodies(chladni_runtime* rt, const std::vector<std::string>& banks,
                              World& w) {
  std::vector<chladni_bank> sounding;
  std::vector<btVector3> halves;
  for (const std::string& path : banks) {
    chladni_bank b = {0};
    check(chladni_bank_load_file(rt, path.c_str(), &b), "load");
    sounding.push_back(b);
    halves.emplace_back(0.05f, 0.05f, 0.05f);
  }
  if (banks.empty()) {
    const double tile[3][3] = {{812, 1960, 3720}, {6, 9, 14}, {2.0, 1.2, 0.6}};
    const double block[3][3] = {{1430, 2980, 5110}, {12, 18, 25}, {1.5, 0.8, 0.4}};
    const double rod[3][3] = {{523, 1441, 2825}, {3, 5, 8}, {2.5, 1.4, 0.7}};
    for (const auto* m : {tile, block, rod}) {
      chladni_bank b = {0};
      check(chladni_bank_from_modes(rt, m[0], m[1], m[2], 3, &b), "modes");
      sounding.push_back(b);
    }
    halves = {{0.08f, 0.08f, 0.006f}, {0.03f, 0.03f, 0.03f}, {0.15f, 0.01f, 0.01f}};
  }
  std::vector<Body> bodies;
  for (std::size_t k = 0; k < sounding.size(); ++k) {
    const btVector3 at(btScalar(0.04 * k), btScalar(-0.03 * k), btScalar(0.25 + 0.2 * k));
    const btQuaternion q(btVector3(1, 0.3f, 0).normalized(), btScalar(0.4 + 0.5 * k));
    bodies.push_back(make_body(rt, sounding[k], halves[k], at, q));
    w.world.addRigidBody(bodies.back().rigid.get());
  }
  return bodies;
}

// A lasting contact's sliding speed goes to the bodies it touches (their fastest this step).
void note_slip(const btPersistentManifold* man, const btManifoldPoint& pt,
               std::vector<Body>& bodies) {
  const btVector3 rel = surface_velocity(man->getBody0(), pt.getPositionWorldOnA()) -
                        surface_velocity(man->getBody1(), pt.getPositionWorldOnB());
  const btVector3& n = pt.m_normalWorldOnB;
  const double slip = (rel - n * rel.dot(n)).length();
  for (Body& b : bodies)
    if (b.rigid.get() == man->getBody0() || b.rigid.get() == man->getBody1())
      b.slip = std::max(b.slip, slip);
}

// A new contact is an impact on each sounding body it touches, in that body's bank frame.
// Returns how many were posted.
int post_impacts(chladni_runtime* rt, const btPersistentManifold* man, const btManifoldPoint& pt,
                 const std::vector<Body>& bodies, double t, uint64_t step, FILE* log) {
  int posted = 0;
  for (int side = 0; side < 2; ++side) {
    const btCollisionObject* o = side == 0 ? man->getBody0() : man->getBody1();
    const auto it = std::find_if(bodies.begin(), bodies.end(),
                                 [&](const Body& b) { return b.rigid.get() == o; });
    if (it == bodies.end()) continue;
    // The impulse pushes this body away from the other.
    const btVector3 n = side == 0 ? pt.m_normalWorldOnB : -pt.m_normalWorldOnB;
    const btMatrix3x3 basis_t = o->getWorldTransform().getBasis().transpose();
    const btVector3 dir = basis_t * n;
    const btVector3 local = (side == 0 ? pt.m_localPointA : pt.m_localPointB) + it->centre;
    chladni_impact im{};
    im.object = it->object;
    im.time = t;
    im.impulse = pt.getAppliedImpulse();
    im.direction[0] = dir.x(), im.direction[1] = dir.y(), im.direction[2] = dir.z();
    im.point[0] = local.x(), im.point[1] = local.y(), im.point[2] = local.z();
    im.vertex = -1;
    im.contact_time = 0.0005;
    check(chladni_impact_post(rt, &im), "impact");
    ++posted;
    std::fprintf(log, "%llu,%.6f,impact,%zu,%.6g,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n",
                 static_cast<unsigned long long>(step), t,
                 static_cast<std::size_t>(it - bodies.begin()), im.impulse, local.x(), local.y(),
                 local.z(), dir.x(), dir.y(), dir.z());
  }
  return posted;
}

// One physics step's contacts: impacts for the new ones, then a scrape for each body sliding.
// Returns whether any impact was posted.
bool post_contacts(chladni_runtime* rt, World& w, std::vector<Body>& bodies, bool scrape, double t,
                   uint64_t step, FILE* log) {
  bool impact = false;
  for (int m = 0; m < w.dispatcher.getNumManifolds(); ++m) {
    const btPersistentManifold* man = w.dispatcher.getManifoldByIndexInternal(m);
    for (int c = 0; c < man->getNumContacts(); ++c) {
      const btManifoldPoint& pt = man->getContactPoint(c);
      if (pt.getLifeTime() > 1 && pt.getAppliedImpulse() > 0) note_slip(man, pt, bodies);
      if (pt.getLifeTime() == 1 && pt.getAppliedImpulse() >= 1e-4f)
        impact |= post_impacts(rt, man, pt, bodies, t, step, log) > 0;
    }
  }
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    Body& b = bodies[k];
    if (scrape && b.slip > kMinSlip) {
      const double energy = std::min(1.0, b.slip / kFullSlip);
      check(chladni_shaker_shake(rt, b.scrape, t, energy), "scrape");
      std::fprintf(log, "%llu,%.6f,scrape,%zu,%.4f,%.4f,,,,,\n",
                   static_cast<unsigned long long>(step), t, k, energy, b.slip);
    }
    b.slip = 0;
  }
  return impact;
}

}  // namespace

int main(int argc, char** argv) try {
  const Options opt = parse_options(argc, argv);
  chladni_config config;
  chladni_config_default(&config);
  config.threads = 1;
  chladni_runtime* rt = nullptr;
  check(chladni_runtime_create(&config, &rt), "create");
  const double fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1}, ear[3] = {0, -1.2, 0.3};
  check(chladni_listener_set(rt, 0, ear, fwd, up), "listener");
  World w;
  std::vector<Body> bodies = make_bodies(rt, opt.banks, w);

  FILE* log = std::fopen(opt.log_path.c_str(), "w");
  if (!log) throw std::runtime_error("cannot write " + opt.log_path);
  // impact: amount is the impulse (N s), the point and normal in the bank's frame;
  // scrape: amount is the shake's energy, x the sliding speed (m/s).
  std::fprintf(log, "frame,time_s,kind,object,amount,x,y,z,nx,ny,nz\n");
  std::vector<float> audio, block(kFramesPerStep * 2);
  double first_impact = -1;
  const uint64_t steps = static_cast<uint64_t>(opt.seconds / kStep);
  for (uint64_t s = 0; s < steps; ++s) {
    const double t = chladni_runtime_time(rt);  // the audio clock is the simulation's
    w.world.stepSimulation(btScalar(kStep), 0);
    for (const Body& b : bodies) post_pose(rt, b, t);
    if (post_contacts(rt, w, bodies, opt.scrape, t, s, log) && first_impact < 0) first_impact = t;
    check(chladni_runtime_render(rt, block.data(), kFramesPerStep), "render");
    audio.insert(audio.end(), block.begin(), block.end());
  }
  std::fclose(log);
  for (Body& b : bodies) w.world.removeRigidBody(b.rigid.get());
  double peak = 0;
  for (float x : audio) peak = std::max(peak, double(std::abs(x)));
  std::vector<float> scaled(audio);  // the WAV peaks at -1 dBFS; the log keeps pascals
  for (float& x : scaled) x = static_cast<float>(x * (peak > 0 ? 0.891 / peak : 1.0));
  write_wav(opt.wav, scaled, 2);
  double first_sound = -1;
  for (std::size_t i = 0; i < audio.size() && first_sound < 0; ++i)
    if (std::abs(audio[i]) > 1e-4 * peak) first_sound = double(i / 2) / kRate;
  std::printf("%zu bodies, %.2f s: first impact at %.6f s, first sound at %.6f s, peak %.3g Pa\n",
              bodies.size(), opt.seconds, first_impact, first_sound, peak);
  std::printf("wrote %s and %s\n", opt.wav.c_str(), opt.log_path.c_str());
  chladni_runtime_destroy(rt);
  return first_impact >= 0 && peak > 0 ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "error: %s\n", e.what());
  return 2;
}
