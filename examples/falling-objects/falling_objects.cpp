// Falling objects: Bullet drops sounding objects onto a floor and into each other; every new
// contact becomes an impact through Chladni's C API, posted at the physics step's time; a body
// resting on a lasting contact slides or rolls on it: its normal force, slip and rolling speed
// and contact point are posted each step as a continuous contact (chladni_contact_post), which
// rings its modes from the floor's surface profile; the audio is rendered in step with the
// simulation (200 frames per 1/240 s step at 48 kHz).
// Writes a stereo float WAV (normalized to -1 dBFS; the peak in pascals is printed) and a
// frame-by-frame event log (CSV), and prints when the first impact happened and when the first
// sound starts.
//
// With --check, the simulation runs again once per body with that body's contact silenced: the
// difference is the contact's own sound, which must be there in every logged contact interval
// and, after a contact ends, decay freely (less energy in its second 50 ms than in its first).
//
// Usage: falling_objects [BANK.chbank ...] [--seconds S] [--no-scrape] [--check] [-o OUT.wav]
//                        [--log EVENTS.csv]
// Without banks, four bodies sound with inline modes (a tile, a block, a rod, and a ball that
// is thrown along the floor and rolls).
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
// Sliding or rolling slower than this is resting (it is still posted: the contact's sound then
// fades with the speed).
constexpr double kMinSpeed = 0.02;  // m/s
// Steps a lasting contact that reports nothing is held over.
constexpr int kHold = 2;

void check(chladni_status s, const char* what) {
  if (s != CHLADNI_OK) throw std::runtime_error(std::string(what) + ": " + chladni_last_error());
}

struct Body {
  chladni_object object{0};
  chladni_contact contact{0};  // its lasting contact with whatever it rests on
  // This step's lasting contacts: their total normal force (N), the fastest slip and rolling
  // speed (m/s), and the point of the one pressing hardest (the bank's frame).
  double force = 0, slip = 0, rolling = 0, hardest = 0;
  btVector3 point;
  // The last step with a lasting contact, and its values: Bullet's resting contacts report no
  // impulse for a step now and then, which is held over rather than heard as a gap.
  chladni_contact_state held{};
  int missed = kHold + 1;
  btVector3 centre;  // the box's centre in the bank's frame: the body's origin
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btDefaultMotionState> motion;
  std::unique_ptr<btRigidBody> rigid;
};

// A sounding body: a box the size of its bank's surface (or `half` for inline modes), or a ball
// of radius `half.x()` where `ball`.
Body make_body(chladni_runtime* rt, chladni_bank bank, btVector3 half, const btVector3& at,
               const btQuaternion& q, bool ball) {
  Body b;
  double lo[3], hi[3];
  b.centre = btVector3(0, 0, 0);
  if (chladni_bank_bounds(rt, bank, lo, hi) == CHLADNI_OK) {
    half = btVector3(btScalar(hi[0] - lo[0]), btScalar(hi[1] - lo[1]), btScalar(hi[2] - lo[2])) / 2;
    b.centre =
        btVector3(btScalar(hi[0] + lo[0]), btScalar(hi[1] + lo[1]), btScalar(hi[2] + lo[2])) / 2;
  }
  for (int c = 0; c < 3; ++c) half[c] = std::max(half[c], btScalar(0.003));
  b.point = b.centre;  // until a lasting contact names one
  if (ball)
    b.shape = std::make_unique<btSphereShape>(half.x());
  else
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
  chladni_contact_desc floor{};
  floor.object = b.object;
  floor.surface = "steel";  // a steel deck: fine-grained, so a slow ball still rings it
  check(chladni_contact_add(rt, &floor, &b.contact), "contact");
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
  bool scrape = true, check = false;
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
    else if (a == "--check")
      o.check = true;
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
    // A 3 cm ball: a solid steel one's modes lie far above hearing; these stand for a hollow
    // toy ball's.
    const double ball[3][3] = {{910, 2130, 3480}, {15, 25, 35}, {1.0, 0.6, 0.3}};
    chladni_bank b = {0};
    check(chladni_bank_from_modes(rt, ball[0], ball[1], ball[2], 3, &b), "modes");
    sounding.push_back(b);
    halves.emplace_back(0.015f, 0.015f, 0.015f);
  }
  std::vector<Body> bodies;
  for (std::size_t k = 0; k < sounding.size(); ++k) {
    const bool ball = banks.empty() && k == 3;
    const btVector3 at =
        ball ? btVector3(-0.3f, 0.2f, 0.05f)
             : btVector3(btScalar(0.04 * k), btScalar(-0.03 * k), btScalar(0.25 + 0.2 * k));
    const btQuaternion q(btVector3(1, 0.3f, 0).normalized(), btScalar(0.4 + 0.5 * k));
    bodies.push_back(make_body(rt, sounding[k], halves[k], at, q, ball));
    btRigidBody* rb = bodies.back().rigid.get();
    if (ball) {  // thrown along the floor: it slides, then rolls
      rb->setLinearVelocity(btVector3(1.5f, -0.2f, 0));
      rb->setRollingFriction(0.002f);
    }
    w.world.addRigidBody(rb);
  }
  return bodies;
}

// A lasting contact, for each sounding body it touches: its normal force (this step's impulse
// over the step), slip (the surfaces' relative tangential speed at the point) and rolling speed
// (how fast the body's centre moves over the other surface, less the slip: a ball rolling
// without slipping rolls at its centre's speed, a box sliding flat rolls at none).
void note_lasting(const btPersistentManifold* man, const btManifoldPoint& pt,
                  std::vector<Body>& bodies) {
  const btVector3& n = pt.m_normalWorldOnB;
  auto tangential = [&](const btVector3& v) { return (v - n * v.dot(n)).length(); };
  const btVector3 rel = surface_velocity(man->getBody0(), pt.getPositionWorldOnA()) -
                        surface_velocity(man->getBody1(), pt.getPositionWorldOnB());
  const double slip = tangential(rel), force = pt.getAppliedImpulse() / kStep;
  for (int side = 0; side < 2; ++side) {
    const btCollisionObject* o = side == 0 ? man->getBody0() : man->getBody1();
    const btCollisionObject* other = side == 0 ? man->getBody1() : man->getBody0();
    for (Body& b : bodies) {
      if (b.rigid.get() != o) continue;
      const btVector3 p = side == 0 ? pt.getPositionWorldOnA() : pt.getPositionWorldOnB();
      const btVector3 centre = b.rigid->getLinearVelocity() - surface_velocity(other, p);
      b.force += force;
      b.slip = std::max(b.slip, slip);
      b.rolling = std::max(b.rolling, std::max(0.0, tangential(centre) - slip));
      if (force > b.hardest) {
        b.hardest = force;
        b.point = (side == 0 ? pt.m_localPointA : pt.m_localPointB) + b.centre;
      }
    }
  }
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
    if (log)
      std::fprintf(log, "%llu,%.6f,impact,%zu,%.6g,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n",
                   static_cast<unsigned long long>(step), t,
                   static_cast<std::size_t>(it - bodies.begin()), im.impulse, local.x(), local.y(),
                   local.z(), dir.x(), dir.y(), dir.z());
  }
  return posted;
}

// One physics step's contacts: impacts for the new ones, then each body's lasting contact as
// its state at the step's end (the runtime interpolates from the last step's to it). Returns
// whether any impact was posted.
bool post_contacts(chladni_runtime* rt, World& w, std::vector<Body>& bodies, bool scrape, int muted,
                   double t, uint64_t step, FILE* log, std::vector<std::vector<uint8_t>>& sliding) {
  bool impact = false;
  for (int m = 0; m < w.dispatcher.getNumManifolds(); ++m) {
    const btPersistentManifold* man = w.dispatcher.getManifoldByIndexInternal(m);
    for (int c = 0; c < man->getNumContacts(); ++c) {
      const btManifoldPoint& pt = man->getContactPoint(c);
      if (pt.getLifeTime() > 1 && pt.getAppliedImpulse() > 0) note_lasting(man, pt, bodies);
      if (pt.getLifeTime() == 1 && pt.getAppliedImpulse() >= 1e-4f)
        impact |= post_impacts(rt, man, pt, bodies, t, step, log) > 0;
    }
  }
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    Body& b = bodies[k];
    const bool moving = b.force > 0 && (b.slip > kMinSpeed || b.rolling > kMinSpeed);
    chladni_contact_state s{};
    if (moving) {
      s.point[0] = b.point.x(), s.point[1] = b.point.y(), s.point[2] = b.point.z();
      s.normal_force = scrape && int(k) != muted ? std::min(b.force, 1e6) : 0.0;
      s.slip_speed = std::min(b.slip, 100.0);
      s.rolling_speed = std::min(b.rolling, 100.0);
      b.held = s;
      b.missed = 0;
    } else if (++b.missed <= kHold) {
      s = b.held;
    } else {
      std::copy(b.held.point, b.held.point + 3, s.point);
    }
    s.time = t + kStep;
    check(chladni_contact_post(rt, b.contact, &s), "contact");
    sliding[k].push_back(s.normal_force > 0);
    if (s.normal_force > 0 && log)
      std::fprintf(log, "%llu,%.6f,%s,%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,\n",
                   static_cast<unsigned long long>(step), t, b.slip >= b.rolling ? "slide" : "roll",
                   k, s.normal_force, s.point[0], s.point[1], s.point[2], b.slip, b.rolling);
    b.force = b.slip = b.rolling = b.hardest = 0;
  }
  return impact;
}

// One run of the simulation with its sound: `muted` (>= 0) silences that body's contact.
struct Run {
  std::vector<float> audio;
  double first_impact = -1;
  std::size_t bodies = 0;
  std::vector<std::vector<uint8_t>> sliding;  // per body, per step: its contact pressed
};

Run simulate(const Options& opt, int muted, FILE* log) {
  chladni_config config;
  chladni_config_default(&config);
  config.threads = 1;
  config.contact_slots = 4096;  // every body's contact: its modes
  chladni_runtime* rt = nullptr;
  check(chladni_runtime_create(&config, &rt), "create");
  const double fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1}, ear[3] = {0, -1.2, 0.3};
  check(chladni_listener_set(rt, 0, ear, fwd, up), "listener");
  World w;
  std::vector<Body> bodies = make_bodies(rt, opt.banks, w);
  Run run;
  run.bodies = bodies.size();
  run.sliding.resize(bodies.size());
  std::vector<float> block(kFramesPerStep * 2);
  const uint64_t steps = static_cast<uint64_t>(opt.seconds / kStep);
  for (uint64_t s = 0; s < steps; ++s) {
    const double t = chladni_runtime_time(rt);  // the audio clock is the simulation's
    w.world.stepSimulation(btScalar(kStep), 0);
    for (const Body& b : bodies) post_pose(rt, b, t);
    if (post_contacts(rt, w, bodies, opt.scrape, muted, t, s, log, run.sliding) &&
        run.first_impact < 0)
      run.first_impact = t;
    check(chladni_runtime_render(rt, block.data(), kFramesPerStep), "render");
    run.audio.insert(run.audio.end(), block.begin(), block.end());
  }
  for (Body& b : bodies) w.world.removeRigidBody(b.rigid.get());
  chladni_runtime_destroy(rt);
  return run;
}

// A body's contact sound (`with` less `without`, its contact silenced), step by step: present in
// each of its contact intervals (rms over 1e-7 Pa; the two runs are otherwise the same to the
// bit), and after each end followed by 100 ms
// without one, decaying freely: the second 50 ms hold under 0.9 of the first's energy, so the
// contact drove it for no longer than that.
struct Checked {
  int intervals = 0, silent = 0, ends = 0, driven_on = 0;
};

void check_body(const std::vector<float>& with, const std::vector<float>& without,
                const std::vector<uint8_t>& sliding, Checked& c) {
  const std::size_t n = sliding.size(), per = 2 * kFramesPerStep;
  std::vector<double> energy(n, 0.0);
  for (std::size_t i = 0; i < n * per; ++i) energy[i / per] += std::pow(with[i] - without[i], 2);
  auto sum = [&](std::size_t a, std::size_t b) {
    double e = 0;
    for (std::size_t k = a; k < std::min(b, n); ++k) e += energy[k];
    return e;
  };
  const std::size_t window = static_cast<std::size_t>(0.05 / kStep);  // 50 ms
  for (std::size_t a = 0; a < n;) {
    if (!sliding[a]) {
      ++a;
      continue;
    }
    std::size_t b = a;
    while (b < n && sliding[b]) ++b;
    ++c.intervals;
    if (std::sqrt(sum(a, b) / double((b - a) * per)) <= 1e-7) ++c.silent;
    bool quiet = b + 2 * window <= n;
    for (std::size_t k = b; quiet && k < b + 2 * window; ++k) quiet = !sliding[k];
    if (quiet) {
      ++c.ends;
      if (!(sum(b + window, b + 2 * window) < 0.9 * sum(b, b + window))) ++c.driven_on;
    }
    a = b;
  }
}

}  // namespace

int main(int argc, char** argv) try {
  const Options opt = parse_options(argc, argv);
  FILE* log = std::fopen(opt.log_path.c_str(), "w");
  if (!log) throw std::runtime_error("cannot write " + opt.log_path);
  // impact: amount is the impulse (N s), the point and normal in the bank's frame;
  // slide and roll: amount is the normal force (N), the point in the bank's frame, nx the slip
  // and ny the rolling speed (m/s).
  std::fprintf(log, "frame,time_s,kind,object,amount,x,y,z,nx,ny,nz\n");
  const Run run = simulate(opt, -1, log);
  std::fclose(log);
  const std::vector<float>& audio = run.audio;
  double peak = 0;
  for (float x : audio) peak = std::max(peak, double(std::abs(x)));
  std::vector<float> scaled(audio);  // the WAV peaks at -1 dBFS; the log keeps pascals
  for (float& x : scaled) x = static_cast<float>(x * (peak > 0 ? 0.891 / peak : 1.0));
  write_wav(opt.wav, scaled, 2);
  double first_sound = -1;
  for (std::size_t i = 0; i < audio.size() && first_sound < 0; ++i)
    if (std::abs(audio[i]) > 1e-4 * peak) first_sound = double(i / 2) / kRate;
  std::printf("%zu bodies, %.2f s: first impact at %.6f s, first sound at %.6f s, peak %.3g Pa\n",
              run.bodies, opt.seconds, run.first_impact, first_sound, peak);
  std::printf("wrote %s and %s\n", opt.wav.c_str(), opt.log_path.c_str());
  bool ok = run.first_impact >= 0 && peak > 0;
  if (opt.check) {
    Checked c;
    for (std::size_t k = 0; k < run.bodies; ++k)
      check_body(audio, simulate(opt, int(k), nullptr).audio, run.sliding[k], c);
    std::printf("contacts: %d intervals, %d without sound; %d ends, %d driven on past 50 ms\n",
                c.intervals, c.silent, c.ends, c.driven_on);
    ok = ok && c.intervals > 0 && c.ends > 0 && c.silent == 0 && c.driven_on == 0;
  }
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "error: %s\n", e.what());
  return 2;
}
