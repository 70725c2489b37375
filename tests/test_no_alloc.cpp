// The audio path allocates nothing: a binary of its own, because it replaces the global
// allocation functions to count calls (and must not share a process with Vulkan layers).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <new>
#include <numbers>

#include "capi_paper_sheet.hpp"
#include "capi_storm.hpp"
#include "chladni/chladni.h"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/modal/synth.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"

namespace {
std::atomic<bool> g_count{false};   // counts every thread's allocations
thread_local bool t_count = false;  // counts this thread's
std::atomic<long> g_allocs{0};
void* counted(std::size_t n) {
  if (g_count.load(std::memory_order_relaxed) || t_count) g_allocs.fetch_add(1);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t n) {
  return counted(n);
}
void* operator new[](std::size_t n) {
  return counted(n);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}

using namespace chladni::runtime;

namespace {
ModeSpec mode(double hz, double decay, float gain = 1) {
  return {2 * std::numbers::pi * hz, decay, gain};
}
constexpr double kFs = 48000;
}  // namespace

TEST(Synth, RenderAndExciteDoNotAllocate) {
  CpuFilterbank fb({.capacity = 4096, .channels = 2, .threads = 2});
  Synth synth(fb, {.sample_rate = kFs, .max_modes = 1024});
  std::vector<ModeSpec> modes;
  for (int i = 0; i < 2000; ++i) modes.push_back(mode(50 + 7 * i, 5.0 + i % 7));
  const auto v = synth.start_voice(modes);
  std::vector<std::complex<float>> amp(modes.size(), {1.0f, 0.5f});
  std::vector<float> out(256 * 2);
  synth.excite(v, amp, 3);  // warm-up: first use of every path
  synth.strike(v, amp, 3.5, 0.001);
  synth.render(256, out.data());
  g_allocs = 0;
  g_count = true;
  for (int b = 0; b < 200; ++b) {
    if (b % 20 == 0) synth.excite(v, amp, static_cast<uint32_t>(b % 256));  // steals too
    if (b % 20 == 10) synth.strike(v, amp, 17.5, 0.002);  // a contact over two renders
    synth.set_pan(v, 0.3f, 0.9f);
    synth.render(256, out.data());
  }
  g_count = false;
  EXPECT_EQ(g_allocs.load(), 0);
  EXPECT_GT(synth.stats().stolen, 0u);
  EXPECT_EQ(synth.stats().contacts_undriven, 0u);
}

TEST(ShakerBank, ShakeRenderAndSharedSynthDoNotAllocate) {
  // A synth and a shaker bank share the filterbank, as render_scene does.
  CpuFilterbank fb({.capacity = 4096, .channels = 2, .threads = 2});
  Synth synth(fb, {.sample_rate = kFs, .max_modes = 2048});
  ShakerBank bank(fb, {.sample_rate = kFs, .slots = 64, .max_voices = 8});
  for (const char* name : {"maraca", "tambourine", "sleighbells", "water"})
    bank.add_voice(instrument_voice(phisem_preset(name), kFs));
  std::vector<ModeSpec> modes;
  for (int i = 0; i < 500; ++i) modes.push_back(mode(80 + 11 * i, 4.0));
  const auto v = synth.start_voice(modes);
  std::vector<std::complex<float>> amp(modes.size(), {1.0f, 0.0f});
  std::vector<float> out(256 * 2), gains(5, 0.7f);
  bank.shake(0, 0.5f, 0);
  synth.render(256, out.data(), bank.prepare(256));  // warm-up
  bank.finish(256);
  g_allocs = 0;
  g_count = true;
  for (int b = 0; b < 200; ++b) {
    for (int k = 0; k < 4; ++k) bank.shake(k, 0.3f, static_cast<uint32_t>((b * 37 + k) % 256));
    if (b % 50 == 0) synth.excite(v, amp, 10);
    bank.set_gains(2, gains, 0.5f, 0.8f);
    const DriveInput in = bank.prepare(256);
    synth.render(256, out.data(), in);
    bank.finish(256);
  }
  g_count = false;
  EXPECT_EQ(g_allocs.load(), 0);
  EXPECT_GT(bank.state(0).collisions, 0u);
}

TEST(CApi, PostingAndRenderingDoNotAllocate) {
  // The game thread's posts and the audio thread's render, with listener moves (gain updates),
  // impacts with contacts, shakes of two shakers, the objects' transfer-free gains, and an
  // object's removal (its fade and stop), after one warm-up render.
  chladni_config c;
  chladni_config_default(&c);
  c.threads = 2;
  chladni_runtime* rt = nullptr;
  ASSERT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_OK);
  std::vector<double> hz, decay, amp;
  for (int i = 0; i < 300; ++i) {
    hz.push_back(60.0 + 61.0 * i);
    decay.push_back(3.0 + i % 7);
    amp.push_back(0.01);
  }
  chladni_bank bank = {0};
  ASSERT_EQ(chladni_bank_from_modes(rt, hz.data(), decay.data(), amp.data(), hz.size(), &bank),
            CHLADNI_OK);
  const double identity[4] = {1, 0, 0, 0}, fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1};
  chladni_object objects[4];
  for (int k = 0; k < 4; ++k) {
    const double at[3] = {k - 1.5, 2.0, 0.0};
    ASSERT_EQ(chladni_object_spawn(rt, bank, at, identity, 1.0, &objects[k]), CHLADNI_OK);
  }
  chladni_shaker gravel{0}, maraca{0};
  const chladni_shaker_desc in_bowl{objects[0], "gravel", 0, 1, 0},
      at_bar{objects[1], "maraca", 0, 0, 0};
  ASSERT_EQ(chladni_shaker_add(rt, &in_bowl, &gravel), CHLADNI_OK);
  ASSERT_EQ(chladni_shaker_add(rt, &at_bar, &maraca), CHLADNI_OK);
  std::vector<float> out(256 * 2);
  ASSERT_EQ(chladni_runtime_render(rt, out.data(), 256), CHLADNI_OK);  // warm-up
  g_allocs = 0;
  g_count = true;
  for (int b = 0; b < 200; ++b) {
    const double t = chladni_runtime_time(rt);
    chladni_impact im{};
    im.object = objects[b % 3];  // object 3 is removed half-way
    im.time = t + 0.001;
    im.impulse = 0.01;
    im.direction[2] = -1;
    im.vertex = -1;
    im.contact_time = b % 2 ? 0.001 : 0.0;
    EXPECT_EQ(chladni_impact_post(rt, &im), CHLADNI_OK);
    const double pos[3] = {0.01 * b, 0, 0};
    EXPECT_EQ(chladni_listener_set(rt, t + 0.002, pos, fwd, up), CHLADNI_OK);
    if (b % 5 == 0) {
      EXPECT_EQ(chladni_shaker_shake(rt, b % 10 ? gravel : maraca, t, 0.7), CHLADNI_OK);
    }
    if (b == 100) {
      EXPECT_EQ(chladni_object_remove(rt, objects[3]), CHLADNI_OK);
    }
    EXPECT_EQ(chladni_runtime_render(rt, out.data(), 256), CHLADNI_OK);
  }
  g_count = false;
  EXPECT_EQ(g_allocs.load(), 0);
  float peak = 0;
  for (float x : out) peak = std::max(peak, std::abs(x));
  EXPECT_GT(peak, 0.0f);
  chladni_runtime_destroy(rt);
}

TEST(CApi, RenderingDoesNotAllocateWhileObjectsSpawnAndGo) {
  // The audio thread's allocations alone, while a control thread spawns and removes objects and
  // loads and releases banks, and a game thread strikes and moves them.
  chladni_runtime* rt = chladni::test::storm_runtime();
  ASSERT_NE(rt, nullptr) << chladni_last_error();
  std::vector<float> out(256 * 2);
  ASSERT_EQ(chladni_runtime_render(rt, out.data(), 256), CHLADNI_OK);  // warm-up
  chladni::test::CApiStorm storm(rt);
  storm.start();
  g_allocs = 0;
  t_count = true;
  float peak = 0;
  const auto t0 = std::chrono::steady_clock::now();  // read before counting: it may not allocate
  while (storm.spawned.load() < 300 &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(30)) {
    if (chladni_runtime_render(rt, out.data(), 256) != CHLADNI_OK) break;
    for (float x : out) peak = std::max(peak, std::abs(x));
  }
  t_count = false;
  storm.stop();
  EXPECT_EQ(g_allocs.load(), 0);
  EXPECT_EQ(storm.unexpected, "");
  EXPECT_GE(storm.spawned.load(), 300);
  EXPECT_GE(storm.shakers_added.load(), 50);  // placed by the audio thread too
  EXPECT_GE(storm.contacts_added.load(), 20);
  EXPECT_GE(storm.contact_states.load(), 20);
  EXPECT_GT(peak, 0.0f);
  storm.clear();
  chladni_runtime_destroy(rt);
}

TEST(CApi, RenderingDoesNotAllocateWhilePaperSheetsPlay) {
  // A crumpled sheet posted frame by frame in modal mode, then removed: the control thread
  // analyses and synthesizes, the audio thread only mixes what it is handed and retires the sheet.
  chladni::test::CApiPaperSheet p;
  ASSERT_NE(p.sheet.id, 0u);
  std::vector<float> out(2 * 735);
  float peak = 0;
  long allocs = 0;
  for (std::uint32_t f = 0; f < p.anim.frame_count() + 60; ++f) {
    if (f < p.anim.frame_count()) {
      ASSERT_EQ(p.post(f), CHLADNI_OK) << chladni_last_error();
    }
    if (f == p.anim.frame_count()) {
      ASSERT_EQ(chladni_paper_remove(p.rt, p.sheet), CHLADNI_OK);
    }
    g_allocs = 0;
    t_count = true;
    const chladni_status s = chladni_runtime_render(p.rt, out.data(), 735);
    t_count = false;
    allocs += g_allocs.load();
    ASSERT_EQ(s, CHLADNI_OK);
    for (float x : out) peak = std::max(peak, std::abs(x));
  }
  EXPECT_EQ(allocs, 0);
  EXPECT_GT(peak, 0.0f);
  EXPECT_TRUE(p.place_given_back());
}

TEST(CApi, RenderingDoesNotAllocateWhileContactsSlideAndRingDown) {
  // A bar scraped and rolled on, its states posted every block (as a physics step would), then
  // the contact removed: the audio thread pushes the states, makes the force, rings the modes
  // down and gives the slots back, all without allocating.
  chladni_config c;
  chladni_config_default(&c);
  c.threads = 1;
  c.contact_slots = 4096;
  c.max_contacts = 1;  // so that adding another shows the first one's place came back
  chladni_runtime* rt = nullptr;
  ASSERT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_OK) << chladni_last_error();
  chladni_bar bar;
  chladni_bar_default(&bar);
  chladni_bank bank{};
  ASSERT_EQ(chladni_bank_from_bar(rt, &bar, &bank), CHLADNI_OK);
  const double pos[3] = {0, 1, 0}, q[4] = {1, 0, 0, 0};
  chladni_object rod{};
  ASSERT_EQ(chladni_object_spawn(rt, bank, pos, q, 1.0, &rod), CHLADNI_OK);
  chladni_contact_desc d{};
  d.object = rod;
  d.surface = "wood";
  chladni_contact contact{};
  ASSERT_EQ(chladni_contact_add(rt, &d, &contact), CHLADNI_OK) << chladni_last_error();
  std::vector<float> out(2 * 256);
  float peak = 0;
  long allocs = 0;
  for (int block = 0; block < 48000 * 9 / 256; ++block) {
    const double now = block * 256 / 48000.0;
    if (block < 200) {
      chladni_contact_state s{};
      s.time = now + 256 / 48000.0;
      s.point[0] = 0.05 + 0.2 * block / 200.0;
      s.point[1] = 0.015;
      s.point[2] = 0.01;
      s.normal_force = 2;
      s.slip_speed = 0.3;
      s.rolling_speed = 0.2;
      ASSERT_EQ(chladni_contact_post(rt, contact, &s), CHLADNI_OK) << chladni_last_error();
    }
    if (block == 200) {
      ASSERT_EQ(chladni_contact_remove(rt, contact), CHLADNI_OK);
    }
    g_allocs = 0;
    t_count = true;
    const chladni_status st = chladni_runtime_render(rt, out.data(), 256);
    t_count = false;
    allocs += g_allocs.load();
    ASSERT_EQ(st, CHLADNI_OK);
    for (float x : out) peak = std::max(peak, std::abs(x));
  }
  EXPECT_EQ(allocs, 0);
  EXPECT_GT(peak, 0.0f);
  // The place came back: the bar's slowest mode decays at about 1/s, 6.9 s to fall by 60 dB.
  chladni_contact again{};
  EXPECT_EQ(chladni_contact_add(rt, &d, &again), CHLADNI_OK) << chladni_last_error();
  chladni_runtime_destroy(rt);
}
