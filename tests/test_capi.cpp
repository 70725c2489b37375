// The C API against the offline renderer: the same objects, impacts and listener move give the
// same samples; the queue's limits and bad input give status codes and messages.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "capi_fixtures.hpp"
#include "chladni/chladni.h"
#include "chladni/core/material.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "test_support.hpp"

using namespace chladni;

namespace {

using Runtime = test::CApiRuntime;

const std::vector<InlineMode> kBowl = {{441, 2.0, 0.02}, {1142, 3.0, 0.01}, {2650, 5.0, 0.004}};
const std::vector<InlineMode> kBar = {{576.5, 4.0, 0.01}, {1589, 7.0, 0.006}};

chladni_bank bank(chladni_runtime* rt, const std::vector<InlineMode>& modes) {
  std::vector<double> f, d, a;
  for (const InlineMode& m : modes) {
    f.push_back(m.frequency);
    d.push_back(m.decay);
    a.push_back(m.amplitude);
  }
  chladni_bank b = {0};
  EXPECT_EQ(chladni_bank_from_modes(rt, f.data(), d.data(), a.data(), f.size(), &b), CHLADNI_OK);
  return b;
}

// The bowl and the bar of the tests, as a scene's objects.
Scene bowl_and_bar(double duration) {
  Scene scene;
  scene.channels = 2;
  scene.duration = duration;
  SceneObject bowl, bar;
  bowl.name = "bowl";
  bowl.position = {0.3, 1.0, 0};
  bowl.modes = kBowl;
  bar.name = "bar";
  bar.position = {-0.5, 2.0, 0};
  bar.modes = kBar;
  scene.objects = {bowl, bar};
  return scene;
}

// The scene rendered offline, on the CPU filterbank.
AudioBuffer offline(const Scene& scene) {
  std::vector<runtime::ObjectModes> objects{runtime::object_modes(scene.objects[0].modes),
                                            runtime::object_modes(scene.objects[1].modes)};
  runtime::CpuFilterbank fb({.capacity = 65536, .channels = 2, .threads = 1});
  return runtime::render_scene(scene, objects, fb, {});
}

// The scene's objects spawned through the C API, in its order.
std::vector<chladni_object> spawn_objects(chladni_runtime* rt, const Scene& scene) {
  const chladni_bank banks[2] = {bank(rt, kBowl), bank(rt, kBar)};
  const double identity[4] = {1, 0, 0, 0};
  std::vector<chladni_object> objects(2, chladni_object{0});
  for (int k = 0; k < 2; ++k) {
    const Vec3& p = scene.objects[k].position;
    EXPECT_EQ(chladni_object_spawn(rt, banks[k], p.data(), identity, 1.0, &objects[k]), CHLADNI_OK);
    EXPECT_NE(objects[k].id, 0u);
  }
  return objects;
}

}  // namespace

TEST(CApi, RendersWhatTheOfflineRendererDoes) {
  // Two objects, three impacts (one with a contact), and the listener stepping closer at a
  // block boundary (512 / 48 kHz), where both apply moves.
  Scene scene = bowl_and_bar(0.5);
  const double times[3] = {0.0101, 0.0333, 0.2}, impulses[3] = {0.01, 0.02, 0.005},
               contacts[3] = {0.0008, 0.0, 0.002};
  const std::size_t which[3] = {0, 1, 0};
  for (int k = 0; k < 3; ++k) {
    ImpactEvent e;
    e.time = times[k];
    e.object = which[k];
    e.impulse = impulses[k];
    e.contact_time = contacts[k];
    scene.events.push_back(e);
  }
  MoveEvent step;
  step.time = 512.0 * 40 / 48000;
  step.position = Vec3{0, 0.6, 0};
  scene.moves = {step};
  const AudioBuffer ref = offline(scene);

  Runtime r;
  const std::vector<chladni_object> objects = spawn_objects(r.rt, scene);
  for (int k = 0; k < 3; ++k) {
    chladni_impact im{};
    im.object = objects[which[k]];
    im.time = times[k];
    im.impulse = impulses[k];
    im.direction[2] = -1;
    im.vertex = -1;
    im.contact_time = contacts[k];
    ASSERT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_OK);
  }
  const double fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1};
  ASSERT_EQ(chladni_listener_set(r.rt, step.time, step.position->data(), fwd, up), CHLADNI_OK);
  // An engine's callback size, unrelated to the runtime's block.
  std::vector<float> out(ref.samples.size());
  for (std::size_t n = 0; n < ref.frames(); n += 480)
    ASSERT_EQ(chladni_runtime_render(r.rt, out.data() + 2 * n, 480), CHLADNI_OK)
        << chladni_last_error();
  const double peak = test::max_abs(ref.samples);
  ASSERT_GT(peak, 1e-4);
  EXPECT_LT(test::max_diff(ref.samples, out), 1e-6 * peak);
}

TEST(CApi, ShakesAsTheOfflineRendererDoes) {
  // Gravel poured into the bowl (the particles ring its modes) and a maraca held at the bar
  // (its own resonances), then the bowl struck while the gravel still rattles.
  Scene scene = bowl_and_bar(0.6);
  ShakeEvent gravel, maraca;
  gravel.time = 0.05;
  gravel.object = 0;
  gravel.instrument = "gravel";
  gravel.energy = 0.8;
  maraca.time = 0.12;
  maraca.object = 1;
  maraca.instrument = "maraca";
  maraca.energy = 0.5;
  maraca.resonate_object = false;
  ShakeEvent again = gravel;
  again.time = 0.3;
  scene.shakes = {gravel, maraca, again};
  ImpactEvent hit;
  hit.time = 0.2;
  hit.impulse = 0.01;
  scene.events = {hit};
  const AudioBuffer ref = offline(scene);

  Runtime r;
  const std::vector<chladni_object> objects = spawn_objects(r.rt, scene);
  chladni_shaker shakers[2] = {{9}, {9}};
  chladni_shaker_desc d{};
  d.object = objects[0];
  d.instrument = "gravel";
  d.resonate_object = 1;
  ASSERT_EQ(chladni_shaker_add(r.rt, &d, &shakers[0]), CHLADNI_OK) << chladni_last_error();
  d.object = objects[1];
  d.instrument = "maraca";
  d.resonate_object = 0;
  ASSERT_EQ(chladni_shaker_add(r.rt, &d, &shakers[1]), CHLADNI_OK) << chladni_last_error();
  EXPECT_NE(shakers[0].id, 0u);
  EXPECT_NE(shakers[1].id, shakers[0].id);
  ASSERT_EQ(chladni_shaker_shake(r.rt, shakers[0], gravel.time, gravel.energy), CHLADNI_OK);
  ASSERT_EQ(chladni_shaker_shake(r.rt, shakers[1], maraca.time, maraca.energy), CHLADNI_OK);
  ASSERT_EQ(chladni_shaker_shake(r.rt, shakers[0], again.time, again.energy), CHLADNI_OK);
  chladni_impact im{};
  im.object = objects[0];
  im.time = hit.time;
  im.impulse = hit.impulse;
  im.direction[2] = -1;
  im.vertex = -1;
  ASSERT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_OK);
  std::vector<float> out(ref.samples.size());
  for (std::size_t n = 0; n < ref.frames(); n += 441)
    ASSERT_EQ(chladni_runtime_render(r.rt, out.data() + 2 * n,
                                     uint32_t(std::min<std::size_t>(441, ref.frames() - n))),
              CHLADNI_OK)
        << chladni_last_error();
  // Silence before the first shake; both shakers sound (the maraca alone before the hit).
  const std::size_t first = static_cast<std::size_t>(gravel.time * 48000);
  EXPECT_EQ(test::max_abs(std::span(out).first(2 * first)), 0.0);
  EXPECT_GT(test::max_abs(std::span(out).subspan(2 * 9600, 2 * 2000)), 0.0);  // 0.2 s
  const double peak = test::max_abs(ref.samples);
  ASSERT_GT(peak, 1e-5);
  EXPECT_LT(test::max_diff(ref.samples, out), 1e-5 * peak);

  // Bad shakers and shakes name what is wrong.
  d.instrument = "kazoo";
  chladni_shaker k{0};
  EXPECT_EQ(chladni_shaker_add(r.rt, &d, &k), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("unknown instrument 'kazoo'"), std::string::npos)
      << chladni_last_error();
  EXPECT_EQ(chladni_shaker_shake(r.rt, {7}, 0.7, 0.5), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("no shaker 7"), std::string::npos);
  EXPECT_EQ(chladni_shaker_shake(r.rt, shakers[0], 0.7, 1.5), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(chladni_shaker_shake(r.rt, shakers[0], NAN, 0.5), CHLADNI_INPUT_ERROR);
  // Removing the bowl silences its gravel and refuses its shakes.
  const double now = chladni_runtime_time(r.rt);
  ASSERT_EQ(chladni_shaker_shake(r.rt, shakers[0], now, 1.0), CHLADNI_OK);
  ASSERT_EQ(chladni_object_remove(r.rt, objects[0]), CHLADNI_OK);
  ASSERT_EQ(chladni_object_remove(r.rt, objects[1]), CHLADNI_OK);
  EXPECT_EQ(chladni_shaker_shake(r.rt, shakers[0], now, 1.0), CHLADNI_INPUT_ERROR);
  std::vector<float> tail(2 * 1024);
  ASSERT_EQ(chladni_runtime_render(r.rt, tail.data(), 512), CHLADNI_OK);  // gains ramp to zero
  ASSERT_EQ(chladni_runtime_render(r.rt, tail.data(), 1024), CHLADNI_OK);
  EXPECT_EQ(test::max_abs(tail), 0.0);
}

TEST(CApi, PlaysAnAnalyticBarAsTheSceneFormatDoes) {
  // The scene format's "bar" object and chladni_bank_bar, both at their defaults (a steel bar),
  // struck at two points along it.
  Scene scene;
  scene.channels = 2;
  scene.duration = 0.4;
  SceneObject bar;
  bar.name = "bar";
  bar.source = SceneObject::Source::Bar;
  bar.position = {0, 1.5, 0};
  scene.objects = {bar};
  const double xs[2] = {0.02, 0.11}, times[2] = {0.01, 0.2};
  for (int k = 0; k < 2; ++k) {
    ImpactEvent e;
    e.time = times[k];
    e.impulse = 0.002;
    e.point = Vec3{xs[k], 0.015, 0.01};
    scene.events.push_back(e);
  }
  auto playable = runtime::resolve_objects(scene);
  std::vector<runtime::ObjectModes> objects{playable[0].modes};
  runtime::CpuFilterbank fb({.capacity = 65536, .channels = 2, .threads = 1});
  const AudioBuffer ref = runtime::render_scene(scene, objects, fb, {});

  Runtime r;
  chladni_bar spec;
  chladni_bar_default(&spec);
  chladni_bank b = {0};
  ASSERT_EQ(chladni_bank_from_bar(r.rt, &spec, &b), CHLADNI_OK) << chladni_last_error();
  EXPECT_EQ(chladni_bank_mode_count(r.rt, b), playable[0].modes.modes.size());
  EXPECT_NEAR(chladni_bank_mass(r.rt, b), 7850 * 0.3 * 0.03 * 0.01, 1e-9);
  const double identity[4] = {1, 0, 0, 0};
  chladni_object id{0};
  ASSERT_EQ(chladni_object_spawn(r.rt, b, bar.position.data(), identity, 1.0, &id), CHLADNI_OK);
  for (int k = 0; k < 2; ++k) {
    chladni_impact im{};
    im.object = id;
    im.time = times[k];
    im.impulse = 0.002;
    im.direction[2] = -1;
    im.vertex = -1;
    im.point[0] = xs[k], im.point[1] = 0.015, im.point[2] = 0.01;
    ASSERT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_OK);
  }
  std::vector<float> out(ref.samples.size());
  ASSERT_EQ(chladni_runtime_render(r.rt, out.data(), uint32_t(ref.frames())), CHLADNI_OK);
  const double peak = test::max_abs(ref.samples);
  ASSERT_GT(peak, 1e-4);
  EXPECT_LT(test::max_diff(ref.samples, out), 1e-6 * peak);
  // Bad bars name the field.
  spec.thickness = INFINITY;
  EXPECT_EQ(chladni_bank_from_bar(r.rt, &spec, &b), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("finite and > 0"), std::string::npos);
  chladni_bar_default(&spec);
  spec.poisson_ratio = 0.7;
  EXPECT_EQ(chladni_bank_from_bar(r.rt, &spec, &b), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("poisson_ratio"), std::string::npos);
}

TEST(CApi, RefusesBadInputAndAFullQueue) {
  Runtime r([](chladni_config& c) { c.queue_capacity = 4; });
  chladni_bank b = bank(r.rt, kBowl);
  const double origin[3] = {0, 1, 0}, identity[4] = {1, 0, 0, 0}, zero[4] = {0, 0, 0, 0};
  chladni_object id{0};
  EXPECT_EQ(chladni_object_spawn(r.rt, b, origin, zero, 1.0, &id), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("orientation"), std::string::npos);
  ASSERT_EQ(chladni_object_spawn(r.rt, b, origin, identity, 1.0, &id), CHLADNI_OK);
  chladni_impact im{};
  im.object = id;
  im.impulse = 0.01;
  im.direction[2] = -1;
  im.vertex = 3;  // inline modes have no surface points
  EXPECT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("vertex 3 is out of range"), std::string::npos);
  im.vertex = -1;
  im.contact_time = INFINITY;
  EXPECT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_INPUT_ERROR);
  im.contact_time = 0;
  // The queue holds 4 commands between renders; the fifth waits for a render.
  for (int k = 0; k < 4; ++k) EXPECT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_OK);
  EXPECT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_QUEUE_FULL);
  std::vector<float> out(256 * 2);
  ASSERT_EQ(chladni_runtime_render(r.rt, out.data(), 256), CHLADNI_OK);
  EXPECT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_OK);
  EXPECT_GT(test::max_abs(out), 0.0);
  ASSERT_EQ(chladni_runtime_render(r.rt, out.data(), 256), CHLADNI_OK);
  // A removed object fades out over the gain ramp (256 samples), without a step, then is
  // silent; it refuses commands at once.
  ASSERT_EQ(chladni_runtime_render(r.rt, out.data(), 256), CHLADNI_OK);
  const double ringing = test::max_abs(out);
  ASSERT_EQ(chladni_object_remove(r.rt, id), CHLADNI_OK);
  ASSERT_EQ(chladni_runtime_render(r.rt, out.data(), 256), CHLADNI_OK);
  EXPECT_GT(test::max_abs(std::span(out).first(128)), 0.3 * ringing);
  EXPECT_LT(test::max_abs(std::span(out).last(16)), 0.1 * ringing);
  ASSERT_EQ(chladni_runtime_render(r.rt, out.data(), 256), CHLADNI_OK);
  EXPECT_EQ(test::max_abs(out), 0.0);
  EXPECT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_INPUT_ERROR);
  chladni_config c;
  chladni_config_default(&c);
  c.channels = 3;
  chladni_runtime* bad = nullptr;
  EXPECT_EQ(chladni_runtime_create(&c, &bad), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(bad, nullptr);
  EXPECT_NE(std::string(chladni_last_error()).find("channels"), std::string::npos);
}

TEST(CApi, PlaysASoundbankFromFileOrMemoryStruckAtAVertex) {
  // A tetrahedron with two modes: every vertex moves along x in mode 0, along y in mode 1.
  Soundbank sb;
  sb.metadata_json = R"({"source":"test"})";
  sb.material = find_material("steel");
  sb.omega = {2 * M_PI * 440, 2 * M_PI * 1000.5};
  sb.decay = {3.5, 12.25};
  sb.residual = {1e-9f, 2e-8f};
  sb.vertices = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.1f}};
  sb.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const float s = float(1 / std::sqrt(3.0));
  sb.normals = {{-s, -s, -s}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int mode = 0; mode < 2; ++mode)
    for (int v = 0; v < 4; ++v)
      for (int c = 0; c < 3; ++c) sb.shapes.push_back(c == mode ? 1.0f : 0.0f);
  const std::string path = test::temp_path("capi_tetra.chbank");
  write_soundbank(path, sb);
  const std::vector<uint8_t> bytes = serialize_soundbank(sb);

  Runtime r;
  chladni_bank from_file = {0};
  chladni_bank from_memory = {0};
  ASSERT_EQ(chladni_bank_load_file(r.rt, path.c_str(), &from_file), CHLADNI_OK)
      << chladni_last_error();
  ASSERT_EQ(chladni_bank_load_memory(r.rt, bytes.data(), bytes.size(), &from_memory), CHLADNI_OK)
      << chladni_last_error();
  EXPECT_EQ(chladni_bank_point_count(r.rt, from_file), 4u);
  EXPECT_EQ(chladni_bank_mode_count(r.rt, from_memory), 2u);
  // The tetrahedron's volume (0.1^3 / 6) times steel's density.
  EXPECT_NEAR(chladni_bank_mass(r.rt, from_memory), 1e-3 / 6 * find_material("steel").density,
              1e-6);
  double lo[3], hi[3];
  ASSERT_EQ(chladni_bank_bounds(r.rt, from_file, lo, hi), CHLADNI_OK);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(lo[c], 0.0, 1e-7);
    EXPECT_NEAR(hi[c], 0.1, 1e-7);
  }
  const double at[3] = {0, 0.5, 0}, identity[4] = {1, 0, 0, 0};
  chladni_object id{0};
  ASSERT_EQ(chladni_object_spawn(r.rt, from_file, at, identity, 1.0, &id), CHLADNI_OK);
  // Struck along x: only mode 0 (440 Hz) moves.
  chladni_impact im{};
  im.object = id;
  im.impulse = 0.01;
  im.direction[0] = 1;
  im.vertex = 1;
  ASSERT_EQ(chladni_impact_post(r.rt, &im), CHLADNI_OK);
  std::vector<float> out(4800 * 2);
  ASSERT_EQ(chladni_runtime_render(r.rt, out.data(), 4800), CHLADNI_OK);
  std::vector<float> left(4800);
  for (int n = 0; n < 4800; ++n) left[n] = out[2 * n];
  EXPECT_GT(test::max_abs(left), 0.0);
  int crossings = 0;  // 440 Hz over 0.1 s: 88 zero crossings
  for (int n = 1; n < 4800; ++n) crossings += (left[n - 1] < 0) != (left[n] < 0);
  EXPECT_NEAR(crossings, 88, 2);
  // Damaged bytes are refused with the section named.
  std::vector<uint8_t> bad = bytes;
  bad.resize(bad.size() / 2);
  chladni_bank broken = {0};
  EXPECT_EQ(chladni_bank_load_memory(r.rt, bad.data(), bad.size(), &broken), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("memory"), std::string::npos)
      << chladni_last_error();
}
