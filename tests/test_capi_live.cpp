// The C API's live scene: places reused under new handles, banks that outlive their release while
// their objects play, capacities that refuse rather than stall, and values that cannot play.
#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "../runtime/capi/src/handles.hpp"
#include "capi_fixtures.hpp"
#include "chladni/chladni.h"
#include "chladni/core/modal_model.hpp"
#include "chladni/core/paper_animation.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/modal/object_modes.hpp"
#include "test_support.hpp"

namespace {

// A runtime with room for `max_objects` objects.
struct LiveRuntime : chladni::test::CApiRuntime {
  explicit LiveRuntime(uint32_t max_objects)
      : CApiRuntime([&](chladni_config& c) { c.max_objects = max_objects; }) {}
};

chladni_bank tone(chladni_runtime* rt, double hz) {
  const double decay = 3.0, amp = 0.02;
  chladni_bank b{0};
  EXPECT_EQ(chladni_bank_from_modes(rt, &hz, &decay, &amp, 1, &b), CHLADNI_OK);
  return b;
}

chladni_status strike(chladni_runtime* rt, chladni_object o, double time) {
  chladni_impact im{};
  im.object = o;
  im.time = time;
  im.impulse = 0.01;
  im.direction[2] = -1;
  im.vertex = -1;
  return chladni_impact_post(rt, &im);
}

bool said(const char* part) {
  return std::string(chladni_last_error()).find(part) != std::string::npos;
}

const double kAt[3] = {0, 1, 0}, kIdentity[4] = {1, 0, 0, 0};

}  // namespace

TEST(CApiLive, PlacesAreReusedUnderNewHandlesOnceTheirObjectHasFaded) {
  LiveRuntime r(2);
  const chladni_bank low = tone(r.rt, 300), high = tone(r.rt, 3000);
  chladni_object a{0}, b{0}, c{0};
  ASSERT_EQ(chladni_object_spawn(r.rt, low, kAt, kIdentity, 1.0, &a), CHLADNI_OK);
  ASSERT_EQ(chladni_object_spawn(r.rt, low, kAt, kIdentity, 1.0, &b), CHLADNI_OK);
  // Both places taken: a clear refusal, not a stall.
  EXPECT_EQ(chladni_object_spawn(r.rt, high, kAt, kIdentity, 1.0, &c), CHLADNI_QUEUE_FULL);
  EXPECT_TRUE(said("max_objects (2)")) << chladni_last_error();
  EXPECT_EQ(c.id, 0u);
  // A strike timed after the removal must not reach whatever takes the place next.
  ASSERT_EQ(strike(r.rt, a, 0.05), CHLADNI_OK);
  ASSERT_EQ(chladni_object_remove(r.rt, a), CHLADNI_OK);
  EXPECT_EQ(strike(r.rt, a, 0.0), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("no object")) << chladni_last_error();
  EXPECT_EQ(chladni_object_remove(r.rt, a), CHLADNI_INPUT_ERROR);
  // Still fading (nothing rendered): the place is not free yet.
  EXPECT_EQ(chladni_object_spawn(r.rt, high, kAt, kIdentity, 1.0, &c), CHLADNI_QUEUE_FULL);
  r.render(512);  // past the 256-sample fade
  ASSERT_EQ(chladni_object_spawn(r.rt, high, kAt, kIdentity, 1.0, &c), CHLADNI_OK);
  EXPECT_EQ(chladni::capi::place_of(c.id), chladni::capi::place_of(a.id));
  EXPECT_NE(c.id, a.id);
  // Until 0.05 s nothing sounds; the old strike is dropped, so the new object stays silent.
  const std::vector<float> quiet = r.render(4800);
  EXPECT_EQ(chladni::test::max_abs(quiet), 0.0);
  // Struck itself, the new object rings at its own 3 kHz (about 600 crossings in 0.1 s).
  ASSERT_EQ(strike(r.rt, c, 0.0), CHLADNI_OK);
  const std::vector<float> out = r.render(4800);
  int crossings = 0;
  for (std::size_t n = 2; n < out.size(); n += 2) crossings += (out[n - 2] < 0) != (out[n] < 0);
  EXPECT_NEAR(crossings, 600, 6);
}

TEST(CApiLive, AReleasedBankPlaysOnUntilItsLastObjectHasFaded) {
  LiveRuntime r(4);
  const chladni_bank bank = tone(r.rt, 500);
  chladni_object a{0}, b{0};
  ASSERT_EQ(chladni_object_spawn(r.rt, bank, kAt, kIdentity, 1.0, &a), CHLADNI_OK);
  ASSERT_EQ(chladni_object_spawn(r.rt, bank, kAt, kIdentity, 1.0, &b), CHLADNI_OK);
  ASSERT_EQ(chladni_bank_release(r.rt, bank), CHLADNI_OK);
  // The handle is refused at once...
  EXPECT_EQ(chladni_bank_mode_count(r.rt, bank), 0u);
  chladni_object c{0};
  EXPECT_EQ(chladni_object_spawn(r.rt, bank, kAt, kIdentity, 1.0, &c), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("released")) << chladni_last_error();
  EXPECT_EQ(chladni_bank_release(r.rt, bank), CHLADNI_INPUT_ERROR);
  // ... but its objects still play, from the bank's modes.
  ASSERT_EQ(strike(r.rt, a, 0.0), CHLADNI_OK);
  EXPECT_GT(chladni::test::max_abs(r.render(1024)), 1e-4);
  EXPECT_EQ(r.rt->banks.size(), 1u);
  ASSERT_EQ(chladni_object_remove(r.rt, a), CHLADNI_OK);
  r.render(512);
  r.rt->reclaim();
  EXPECT_EQ(r.rt->banks.size(), 1u);  // b still holds it
  ASSERT_EQ(chladni_object_remove(r.rt, b), CHLADNI_OK);
  r.render(512);
  r.rt->reclaim();
  EXPECT_TRUE(r.rt->banks.empty());
  EXPECT_EQ(r.rt->free_places.size(), 4u);
}

TEST(CApiLive, ValuesThatCannotPlayAreRefusedNamingTheArgument) {
  LiveRuntime r(4);
  const chladni_bank bank = tone(r.rt, 500);
  chladni_object o{0};
  EXPECT_EQ(chladni_object_spawn(r.rt, bank, kAt, kIdentity, -1.0, &o), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("gain must be in [0, 1e6]")) << chladni_last_error();
  EXPECT_EQ(chladni_object_spawn(r.rt, bank, kAt, kIdentity, NAN, &o), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(chladni_object_spawn(r.rt, bank, kAt, kIdentity, 1e300, &o), CHLADNI_INPUT_ERROR);
  const double far[3] = {0, 1e300, 0};  // finite, but its squared distance is not
  EXPECT_EQ(chladni_object_spawn(r.rt, bank, far, kIdentity, 1.0, &o), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("within 1e9 m")) << chladni_last_error();
  const double nan_at[3] = {0, NAN, 0};
  EXPECT_EQ(chladni_object_spawn(r.rt, bank, nan_at, kIdentity, 1.0, &o), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("position must be finite")) << chladni_last_error();
  EXPECT_EQ(chladni_object_spawn(r.rt, chladni_bank{77}, kAt, kIdentity, 1.0, &o),
            CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("no bank 77")) << chladni_last_error();
  ASSERT_EQ(chladni_object_spawn(r.rt, bank, kAt, kIdentity, 1.0, &o), CHLADNI_OK);
  // An impulse whose kick no float holds.
  chladni_impact huge{};
  huge.object = o;
  huge.impulse = 1e300;
  huge.direction[2] = -1;
  huge.vertex = -1;
  EXPECT_EQ(chladni_impact_post(r.rt, &huge), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("impulse must be in (0, 1e6] N s")) << chladni_last_error();
  // Times: forever ahead, infinite, NaN.
  EXPECT_EQ(strike(r.rt, o, 1e300), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("horizon")) << chladni_last_error();
  EXPECT_EQ(strike(r.rt, o, INFINITY), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(chladni_object_move(r.rt, o, NAN, kAt, kIdentity), CHLADNI_INPUT_ERROR);
  const double fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
  EXPECT_EQ(chladni_listener_set(r.rt, 1e9, kAt, fwd, up), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(chladni_listener_set(r.rt, 0, kAt, zero, up), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("forward must not be zero")) << chladni_last_error();
  EXPECT_EQ(strike(r.rt, o, 59.0), CHLADNI_OK);  // within the default 60 s horizon
  // Handles never spawned, and the null one.
  EXPECT_EQ(strike(r.rt, chladni_object{(uint64_t{9} << 32) | 1}, 0), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(strike(r.rt, chladni_object{0}, 0), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(chladni_object_remove(r.rt, chladni_object{123}), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(chladni_bank_release(r.rt, chladni_bank{0}), CHLADNI_INPUT_ERROR);
  double lo[3], hi[3];
  EXPECT_EQ(chladni_bank_bounds(r.rt, chladni_bank{5}, lo, hi), CHLADNI_INPUT_ERROR);
  chladni_config c;
  chladni_config_default(&c);
  c.horizon = 0;
  chladni_runtime* bad = nullptr;
  EXPECT_EQ(chladni_runtime_create(&c, &bad), CHLADNI_INPUT_ERROR);
  EXPECT_TRUE(said("horizon")) << chladni_last_error();
}

namespace {

// Two modes radiating as a monopole (500 Hz) and a z dipole (900 Hz) from a 0.1 m sphere.
chladni::ModalModel dipole_model() {
  chladni::ModalModel model;
  model.name = "dipole";
  model.omega = {2 * M_PI * 500, 2 * M_PI * 900};
  model.decay = {1.0, 1.0};
  model.radiation = {1.0, 1.0};
  chladni::Transfer t;
  t.radius = 0.1;
  chladni::ModeTransfer m;
  m.order = 1;
  m.wavenumber = model.omega[0] / 343.0;
  t.add_mode(m, {{1, 0}, 0, 0, 0});
  m.wavenumber = model.omega[1] / 343.0;
  t.add_mode(m, {0, 0, {1, 0}, 0});
  model.transfer = t;
  return model;
}

}  // namespace

TEST(CApiLive, AnInstalledObjectWithTransferSoundsAsAnAddedOne) {
  // The live path's own transfer table against the player's shared one: the same strikes, pose
  // and listener moves (onto the dipole's axis, then broadside) give the same samples.
  using namespace chladni;
  const ModalModel model = dipole_model();
  const runtime::ObjectModes modes = runtime::object_modes(model);
  ASSERT_NE(modes.transfer, nullptr);
  const std::unique_ptr<runtime::TransferTable> table =
      runtime::object_transfer_table(*modes.transfer, false);
  auto play = [&](bool live) {
    runtime::CpuFilterbank fb({.capacity = 64, .channels = 2, .threads = 1});
    runtime::PlayerOptions po;
    po.max_objects = 1;
    po.map_gain_modes = 4096;  // the series, as the live table without maps
    runtime::ScenePlayer player(fb, po);
    const Quat turned{std::cos(0.3), std::sin(0.3), 0, 0};
    if (live) {
      player.finish_objects();
      auto prepared = player.prepare_object(modes, table.get(), {0, 0, 0}, turned, 0.7);
      EXPECT_TRUE(player.install(0, *prepared));
    } else {
      player.add_object(modes, {0, 0, 0}, turned, 0.7);
    }
    std::vector<float> out(2 * 256 * 40);
    ImpactEvent hit;
    hit.impulse = 1.0;
    hit.direction = {0, 0, 1};
    for (int b = 0; b < 40; ++b) {
      if (b == 0 || b == 20) player.impact(0, hit, 3.5);
      if (b == 10) player.set_listener({{0, 0.2, 1.5}, {0, 0, -1}, {0, 1, 0}});
      if (b == 30) player.set_listener({{1.5, 0, 0}, {-1, 0, 0}, {0, 0, 1}});
      player.render(256, out.data() + 2 * 256 * b);
    }
    return out;
  };
  const std::vector<float> added = play(false), live = play(true);
  const double peak = test::max_abs(added);
  ASSERT_GT(peak, 1e-5);
  EXPECT_LT(test::max_diff(added, live), 1e-6 * peak);
  // Broadside (the last quarter) the dipole is silent: only the 500 Hz monopole is left, so the
  // level there falls well below the axis' (the second quarter), where both sound.
  const std::size_t q = added.size() / 4;
  const double axis = test::max_abs(std::span(live).subspan(q, q)),
               side = test::max_abs(std::span(live).subspan(3 * q + q / 2, q / 2));
  EXPECT_GT(axis, 0.0);
  EXPECT_LT(side, axis);
}

TEST(CApiLive, ShakersComeAndGoWhileTheirObjectPlays) {
  chladni::test::CApiRuntime r([](chladni_config& c) { c.max_shakers = 2; });
  chladni_runtime* rt = r.rt;
  auto render = [&](uint32_t frames) { return r.render(frames); };
  const chladni_bank bank = tone(rt, 700);
  chladni_object bowl{0}, bar{0};
  ASSERT_EQ(chladni_object_spawn(rt, bank, kAt, kIdentity, 1.0, &bowl), CHLADNI_OK);
  ASSERT_EQ(chladni_object_spawn(rt, bank, kAt, kIdentity, 1.0, &bar), CHLADNI_OK);
  const chladni_shaker_desc maraca{bowl, "maraca", 0, 0, 0}, gravel{bowl, "gravel", 0, 1, 0};
  chladni_shaker a{0}, b{0}, extra{0};
  ASSERT_EQ(chladni_shaker_add(rt, &maraca, &a), CHLADNI_OK) << chladni_last_error();
  ASSERT_EQ(chladni_shaker_add(rt, &gravel, &b), CHLADNI_OK) << chladni_last_error();
  // Both places taken: refused, not a stall.
  EXPECT_EQ(chladni_shaker_add(rt, &maraca, &extra), CHLADNI_QUEUE_FULL);
  EXPECT_TRUE(said("max_shakers (2)")) << chladni_last_error();
  // Shaken while the audio plays, the maraca sounds.
  ASSERT_EQ(chladni_shaker_shake(rt, a, 0.0, 1.0), CHLADNI_OK);
  EXPECT_GT(chladni::test::max_abs(render(4800)), 0.0);
  // Removed: its shakes are refused at once; it fades out over the gain ramp, then is silent,
  // and its place takes a new shaker under a new handle.
  ASSERT_EQ(chladni_shaker_shake(rt, a, chladni_runtime_time(rt), 1.0), CHLADNI_OK);
  render(256);
  ASSERT_EQ(chladni_shaker_remove(rt, a), CHLADNI_OK);
  EXPECT_EQ(chladni_shaker_shake(rt, a, chladni_runtime_time(rt), 1.0), CHLADNI_INPUT_ERROR);
  EXPECT_EQ(chladni_shaker_remove(rt, a), CHLADNI_INPUT_ERROR);
  const std::vector<float> fade = render(256);
  EXPECT_GT(chladni::test::max_abs(std::span(fade).first(64)), 0.0);  // no step to silence
  EXPECT_EQ(chladni::test::max_abs(render(256)), 0.0);
  ASSERT_EQ(chladni_shaker_add(rt, &maraca, &extra), CHLADNI_OK) << chladni_last_error();
  EXPECT_EQ(chladni::capi::place_of(extra.id), chladni::capi::place_of(a.id));
  EXPECT_NE(extra.id, a.id);
  // The object's removal takes its shakers with it: their handles are refused, and once faded
  // their places are free for the other object.
  ASSERT_EQ(chladni_object_remove(rt, bowl), CHLADNI_OK);
  EXPECT_EQ(chladni_shaker_shake(rt, b, chladni_runtime_time(rt), 1.0), CHLADNI_INPUT_ERROR);
  render(512);
  const chladni_shaker_desc at_bar{bar, "maraca", 0, 0, 0};
  chladni_shaker c1{0}, c2{0};
  ASSERT_EQ(chladni_shaker_add(rt, &at_bar, &c1), CHLADNI_OK) << chladni_last_error();
  ASSERT_EQ(chladni_shaker_add(rt, &at_bar, &c2), CHLADNI_OK) << chladni_last_error();
  EXPECT_EQ(chladni_shaker_remove(rt, b), CHLADNI_INPUT_ERROR);
  ASSERT_EQ(chladni_shaker_shake(rt, c2, chladni_runtime_time(rt), 1.0), CHLADNI_OK);
  EXPECT_GT(chladni::test::max_abs(render(2400)), 0.0);
}

TEST(CApiLive, RandomCallSequencesNeverCrashAndGiveEverythingBack) {
  // Hostile use: valid, stale and made-up handles, NaN and huge values, renders of any size,
  // banks released under live objects, paper sheets posted frames of any shape (crushed to a
  // point, flung 1e8 m, NaN), contacts between any objects posted any values, all interleaved
  // at random.
  chladni::test::CApiRuntime r([](chladni_config& c) {
    c.max_objects = 8;
    c.contact_slots = 4096;
  });
  const std::string paper_path = CHLADNI_SOURCE_DIR "/meshes/paper/crumple.json";
  const chladni::PaperAnimation paper = chladni::load_paper_animation(paper_path);
  std::vector<chladni_paper> papers;
  std::mt19937 rng(2026);
  std::vector<chladni_bank> banks;
  std::vector<chladni_object> objects;
  std::vector<chladni_shaker> shakers;
  std::vector<chladni_contact> contacts;
  int posted = 0;
  const double weird[] = {0.0, -1.0, 1e300, NAN, INFINITY, 0.01, 2.0};
  auto pick = [&](auto& v, auto junk) {
    return v.empty() || rng() % 5 == 0 ? junk : v[rng() % v.size()];
  };
  auto any = [&] { return weird[rng() % std::size(weird)]; };
  for (int step = 0; step < 4000; ++step) {
    chladni_status s = CHLADNI_OK;
    const double t = chladni_runtime_time(r.rt) + (rng() % 3 ? 0.001 : any());
    switch (rng() % 11) {
      case 0:
        banks.push_back(tone(r.rt, 200 + rng() % 4000));
        break;
      case 1:
        s = chladni_bank_release(r.rt, pick(banks, chladni_bank{rng()}));
        break;
      case 2: {
        chladni_object o{0};
        const double at[3] = {any(), 1, 0};
        s = chladni_object_spawn(r.rt, pick(banks, chladni_bank{rng()}), rng() % 4 ? kAt : at,
                                 kIdentity, rng() % 4 ? 1.0 : any(), &o);
        if (s == CHLADNI_OK) objects.push_back(o);
        break;
      }
      case 3:
        s = chladni_object_remove(r.rt, pick(objects, chladni_object{rng()}));
        break;
      case 4: {
        chladni_impact im{};
        im.object = pick(objects, chladni_object{rng()});
        im.time = t;
        im.impulse = rng() % 3 ? 0.01 : any();
        im.direction[2] = rng() % 4 ? -1 : 0;
        im.vertex = rng() % 5 ? -1 : int64_t(rng() % 10);
        s = chladni_impact_post(r.rt, &im);
        break;
      }
      case 5: {
        const chladni_shaker_desc d{pick(objects, chladni_object{rng()}),
                                    rng() % 2 ? "maraca" : "gravel", 0, int(rng() % 2), 0};
        chladni_shaker k{0};
        s = chladni_shaker_add(r.rt, &d, &k);
        if (s == CHLADNI_OK) shakers.push_back(k);
        break;
      }
      case 6:
        s = rng() % 2 ? chladni_shaker_remove(r.rt, pick(shakers, chladni_shaker{rng()}))
                      : chladni_shaker_shake(r.rt, pick(shakers, chladni_shaker{rng()}), t,
                                             rng() % 3 ? 0.5 : any());
        break;
      case 7:
        s = chladni_object_move(r.rt, pick(objects, chladni_object{rng()}), t, kAt, kIdentity);
        break;
      case 8: {
        const uint32_t what = rng() % 8;
        if (what == 0) {
          chladni_paper_desc d{};
          d.animation = paper_path.c_str();
          d.listener[4] = rng() % 4 ? 0 : any();
          chladni_paper p{0};
          s = chladni_paper_add(r.rt, &d, &p);
          if (s == CHLADNI_OK) papers.push_back(p);
        } else if (what == 1) {
          s = chladni_paper_remove(r.rt, pick(papers, chladni_paper{rng()}));
        } else {
          const std::span<const float> f = paper.frame(rng() % paper.frame_count());
          std::vector<float> x(f.begin(), f.end());
          const double warp = rng() % 3 ? 1.0 : any();  // crushed, flung, mirrored, NaN
          for (float& c : x) c = float(c * warp);
          const uint32_t held = rng() % (paper.vertex_count + 2);
          s = chladni_paper_post_frame(r.rt, pick(papers, chladni_paper{rng()}), x.data(),
                                       rng() % 6 ? paper.vertex_count : uint32_t(rng() % 400),
                                       rng() % 3 ? nullptr : &held, 1);
        }
        break;
      }
      case 9: {  // contacts: added between any objects, posted any values, removed
        const uint32_t what = rng() % 4;
        if (what == 0) {
          chladni_contact_desc d{};
          d.object = pick(objects, chladni_object{rng()});
          d.other = rng() % 3 ? chladni_object{0} : pick(objects, chladni_object{rng()});
          d.surface = rng() % 4 ? "steel" : "velvet";
          d.level = rng() % 4 ? 0.0 : any();
          chladni_contact k{};
          s = chladni_contact_add(r.rt, &d, &k);
          if (s == CHLADNI_OK) contacts.push_back(k);
        } else if (what == 1) {
          s = chladni_contact_remove(r.rt, pick(contacts, chladni_contact{rng()}));
        } else {
          chladni_contact_state st{};
          st.time = rng() % 4 ? t : any();
          for (double& x : st.point) x = rng() % 4 ? 0.0 : any();
          st.normal_force = rng() % 3 ? 1.0 : any();
          st.slip_speed = rng() % 3 ? 0.3 : any();
          st.rolling_speed = rng() % 3 ? 0.1 : any();
          s = chladni_contact_post(r.rt, pick(contacts, chladni_contact{rng()}), &st);
          posted += s == CHLADNI_OK;
        }
        break;
      }
      default: {
        std::vector<float> out = r.render(uint32_t(rng() % 700));
        for (float x : out) ASSERT_TRUE(std::isfinite(x));
      }
    }
    ASSERT_TRUE(s == CHLADNI_OK || s == CHLADNI_INPUT_ERROR || s == CHLADNI_QUEUE_FULL)
        << "step " << step << ": " << chladni_last_error();
  }
  for (chladni_shaker k : shakers) chladni_shaker_remove(r.rt, k);
  for (chladni_object o : objects) chladni_object_remove(r.rt, o);
  for (chladni_bank b : banks) chladni_bank_release(r.rt, b);
  for (chladni_paper p : papers) chladni_paper_remove(r.rt, p);
  for (chladni_contact k : contacts) chladni_contact_remove(r.rt, k);
  // What the sheets buffered (up to 1.5 s) and their tails, the contacts' ring-down (2.3 s for
  // these tones), then silence.
  for (int k = 0; k < 4; ++k)
    for (float x : r.render(48000)) ASSERT_TRUE(std::isfinite(x));
  EXPECT_EQ(chladni::test::max_abs(r.render(256)), 0.0);
  r.rt->reclaim();
  EXPECT_TRUE(r.rt->banks.empty());
  EXPECT_EQ(r.rt->free_places.size(), 8u);
  EXPECT_EQ(r.rt->free_shaker_places.size(), r.rt->max_shakers());
  EXPECT_EQ(r.rt->free_paper_places.size(), r.rt->config.max_papers);
  EXPECT_EQ(r.rt->free_contact_places.size(), r.rt->max_contacts());
  EXPECT_GE(contacts.size(), 5u);  // the contacts were played, not only refused
  EXPECT_GE(posted, 3);
}
