// Continuous contacts through the C API: states posted per physics step sound as the scene
// format renders the same trajectory; bad states are refused naming the call; a removed contact
// rings down and gives its place back.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "capi_fixtures.hpp"
#include "chladni/chladni.h"
#include "chladni/runtime/scene/prepare_scene.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {

constexpr int kSteps = 26;
constexpr uint64_t kFirst = 4096, kStep = 1024;  // samples: every point on a block boundary

double capi_contact_force(int i) {
  return 1.0 + 0.5 * std::sin(0.3 * i);
}
double capi_contact_slip(int i) {
  return 0.1 + 0.02 * i;
}
double capi_contact_roll(int i) {
  return 0.3 - 0.01 * i;
}
double capi_contact_x(int i) {
  return 0.03 + 0.009 * i;
}

// The same trajectory as a scene: a default bar 1 m in front of the listener.
Scene capi_contact_scene() {
  nlohmann::json force, slip, roll, point;
  for (int i = 0; i < kSteps; ++i) {
    force.push_back(capi_contact_force(i));
    slip.push_back(capi_contact_slip(i));
    roll.push_back(capi_contact_roll(i));
    point.push_back({capi_contact_x(i), 0.015, 0.01});
  }
  nlohmann::json scene = {
      {"sample_rate", 48000},
      {"channels", 2},
      {"duration", 1.0},
      {"objects",
       {{{"name", "rod"}, {"position", {0.2, 1, 0}}, {"bar", nlohmann::json::object()}}}},
      {"events",
       {{{"type", "contact"},
         {"time", double(kFirst) / 48000},
         {"object", "rod"},
         {"rate", 48000.0 / kStep},
         {"force", force},
         {"slip", slip},
         {"rolling", roll},
         {"point", point},
         {"roughness", {{"surface", "steel"}}}}}}};
  return parse_scene(scene, ".");
}

struct BarContact {
  chladni_bank bank{};
  chladni_object rod{};
  chladni_contact contact{};
  explicit BarContact(chladni_runtime* rt, uint64_t seed = 4097) {
    chladni_bar bar;
    chladni_bar_default(&bar);
    EXPECT_EQ(chladni_bank_from_bar(rt, &bar, &bank), CHLADNI_OK) << chladni_last_error();
    const double pos[3] = {0.2, 1, 0}, q[4] = {1, 0, 0, 0};
    EXPECT_EQ(chladni_object_spawn(rt, bank, pos, q, 1.0, &rod), CHLADNI_OK);
    chladni_contact_desc d{};
    d.object = rod;
    d.surface = "steel";
    d.seed = seed;  // the scene player seeds its first contact so
    EXPECT_EQ(chladni_contact_add(rt, &d, &contact), CHLADNI_OK) << chladni_last_error();
  }
};

chladni_contact_state capi_contact_state(int i) {
  chladni_contact_state s{};
  // A quarter sample early: the runtime's first sample at or after it is the point's.
  s.time = (double(kFirst + kStep * i) - 0.25) / 48000;
  s.point[0] = capi_contact_x(i);
  s.point[1] = 0.015;
  s.point[2] = 0.01;
  s.normal_force = capi_contact_force(i);
  s.slip_speed = capi_contact_slip(i);
  s.rolling_speed = capi_contact_roll(i);
  return s;
}

}  // namespace

TEST(CApiContact, PostedStatesSoundAsTheSceneRendersThem) {
  const Scene scene = capi_contact_scene();
  SceneSettings settings;
  settings.filterbank.threads = 1;
  PreparedScene prepared = prepare_scene(scene, settings);
  const AudioBuffer offline = render_scene(scene, prepared);
  const double peak = test::max_abs(offline.samples);
  ASSERT_GT(peak, 0);

  test::CApiRuntime r([](chladni_config& c) { c.contact_slots = 4096; });
  BarContact b(r.rt);
  std::vector<float> live;
  auto render = [&](uint32_t frames) {
    const std::vector<float> out = r.render(frames);
    live.insert(live.end(), out.begin(), out.end());
  };
  render(256);  // the contact is placed at the first render, its states queued after
  for (int i = 0; i < kSteps; ++i) {
    const chladni_contact_state s = capi_contact_state(i);
    ASSERT_EQ(chladni_contact_post(r.rt, b.contact, &s), CHLADNI_OK) << chladni_last_error();
  }
  // Up to the last state's sample, then the contact ends there, as the scene's does.
  render(uint32_t(kFirst + kStep * (kSteps - 1) - 256));
  ASSERT_EQ(chladni_contact_remove(r.rt, b.contact), CHLADNI_OK);
  render(uint32_t(offline.frames() - live.size() / 2));
  ASSERT_EQ(live.size(), offline.samples.size());
  EXPECT_LT(test::max_diff(live, offline.samples), 1e-5 * peak);
  // A one-step shift of the trajectory is far off (the comparison can fail).
  std::vector<float> shifted(live.size(), 0.0f);
  std::copy(live.begin(), live.end() - 2 * kStep, shifted.begin() + 2 * kStep);
  EXPECT_GT(test::max_diff(shifted, offline.samples), 0.1 * peak);
}

TEST(CApiContact, RefusesWhatCannotPlayNamingTheCall) {
  test::CApiRuntime r([](chladni_config& c) {
    c.contact_slots = 4096;
    c.max_contacts = 1;
  });
  BarContact b(r.rt);
  r.render(256);
  auto refused = [&](chladni_contact_state s, const std::string& what) {
    EXPECT_EQ(chladni_contact_post(r.rt, b.contact, &s), CHLADNI_INPUT_ERROR) << what;
    EXPECT_NE(std::string(chladni_last_error()).find("chladni_contact_post: " + what),
              std::string::npos)
        << chladni_last_error();
  };
  chladni_contact_state s = capi_contact_state(0);
  s.normal_force = NAN;
  refused(s, "normal_force (N) must be in [0,");
  s = capi_contact_state(0);
  s.slip_speed = INFINITY;
  refused(s, "slip_speed (m/s) must be in [0,");
  s = capi_contact_state(0);
  s.rolling_speed = -1;
  refused(s, "rolling_speed (m/s) must be in [0,");
  s = capi_contact_state(0);
  s.point[2] = 3;  // the bar is 1 cm thick
  refused(s, "point (0.030000, 0.015000, 3.000000) lies off its body");
  s = capi_contact_state(0);
  s.point[0] = NAN;
  refused(s, "point");
  // A second contact: no place (QUEUE_FULL); other == object; an unknown surface; stale handles.
  chladni_contact_desc d{};
  d.object = b.rod;
  chladni_contact more{};
  EXPECT_EQ(chladni_contact_add(r.rt, &d, &more), CHLADNI_QUEUE_FULL);
  d.other = b.rod;
  EXPECT_EQ(chladni_contact_add(r.rt, &d, &more), CHLADNI_INPUT_ERROR);
  d.other = chladni_object{0};
  d.surface = "velvet";
  ASSERT_EQ(chladni_contact_remove(r.rt, b.contact), CHLADNI_OK);
  s = capi_contact_state(0);
  EXPECT_EQ(chladni_contact_post(r.rt, b.contact, &s), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(chladni_contact_remove(r.rt, b.contact), CHLADNI_INPUT_ERROR);
  // The removed contact's place comes back once its modes have rung down (the bar's slowest
  // mode decays at about 1/s: 6.9 s to fall by 60 dB).
  EXPECT_EQ(chladni_contact_add(r.rt, &d, &more), CHLADNI_INPUT_ERROR);  // velvet
  EXPECT_NE(std::string(chladni_last_error()).find("unknown surface 'velvet'"), std::string::npos);
  d.surface = nullptr;
  int renders = 0;
  chladni_status st;
  while ((st = chladni_contact_add(r.rt, &d, &more)) == CHLADNI_QUEUE_FULL && renders < 400) {
    r.render(4800);
    ++renders;
  }
  EXPECT_EQ(st, CHLADNI_OK) << chladni_last_error();
  EXPECT_GT(renders, 60);  // not before its ring-down
  // An object's removal ends its contacts: their posts are refused.
  r.render(256);
  ASSERT_EQ(chladni_object_remove(r.rt, b.rod), CHLADNI_OK);
  s = capi_contact_state(0);
  EXPECT_EQ(chladni_contact_post(r.rt, more, &s), CHLADNI_INPUT_ERROR);
  // Without contact slots there are no contacts.
  test::CApiRuntime none;  // contact_slots = 0 by default
  chladni_bar bar;
  chladni_bar_default(&bar);
  chladni_bank nbank{};
  ASSERT_EQ(chladni_bank_from_bar(none.rt, &bar, &nbank), CHLADNI_OK);
  const double pos[3] = {0, 1, 0}, q[4] = {1, 0, 0, 0};
  chladni_object nrod{};
  ASSERT_EQ(chladni_object_spawn(none.rt, nbank, pos, q, 1.0, &nrod), CHLADNI_OK);
  chladni_contact_desc nd{};
  nd.object = nrod;
  EXPECT_EQ(chladni_contact_add(none.rt, &nd, &more), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("contact_slots = 0"), std::string::npos);
}
