// The runtime's multi-threaded paths: a game thread posting through the C API's queue while the
// audio thread renders, a control thread posting paper frames, the CPU filterbank's worker
// threads and the shakers' excitation threads.
// Each gives the samples of its single-threaded run. CI also runs these under ThreadSanitizer
// (scripts/tsan.sh), which fails them on any data race.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "../runtime/capi/src/handles.hpp"
#include "capi_paper_sheet.hpp"
#include "capi_storm.hpp"
#include "chladni/chladni.h"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/phisem/phisem.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {

constexpr int kObjects = 4;
constexpr int kCommands = 1500;
constexpr double kFirst = 1.0;  // s: the commands' times start here
constexpr uint32_t kBlock = 256;
constexpr int kBlocks = 300;  // 1.6 s

double max_abs(const std::vector<float>& v) {
  double m = 0;
  for (float x : v) m = std::max(m, double(std::abs(x)));
  return m;
}

// A fresh runtime's k-th object: place k, generation 1.
uint64_t object_id(int k) {
  return (uint64_t{1} << 32) | static_cast<uint64_t>(k);
}

chladni_runtime* make_runtime() {
  chladni_config c;
  chladni_config_default(&c);
  c.threads = 2;
  chladni_runtime* rt = nullptr;
  EXPECT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_OK) << chladni_last_error();
  std::vector<double> hz, decay, amp;
  for (int i = 0; i < 120; ++i) {
    hz.push_back(90.0 + 97.0 * i);
    decay.push_back(4.0 + i % 5);
    amp.push_back(0.01);
  }
  chladni_bank bank = {0};
  EXPECT_EQ(chladni_bank_from_modes(rt, hz.data(), decay.data(), amp.data(), hz.size(), &bank),
            CHLADNI_OK);
  const double identity[4] = {1, 0, 0, 0};
  chladni_object first{0};
  for (int k = 0; k < kObjects; ++k) {
    const double at[3] = {k - 1.5, 2.0, 0.0};
    chladni_object id{0};
    EXPECT_EQ(chladni_object_spawn(rt, bank, at, identity, 1.0, &id), CHLADNI_OK);
    EXPECT_EQ(id.id, object_id(k));  // the k-th place, first generation, in every runtime
    if (k == 0) first = id;
  }
  const chladni_shaker_desc gravel{first, "gravel", 0, 1, 0};
  chladni_shaker shaker{0};
  EXPECT_EQ(chladni_shaker_add(rt, &gravel, &shaker), CHLADNI_OK) << chladni_last_error();
  EXPECT_EQ(shaker.id, object_id(0));  // shaker place 0, generation 1
  return rt;
}

// Command k: an impact, a move, a listener step or a shake, at kFirst + k ms. Retries while the
// queue is full (the audio thread drains it).
void post(chladni_runtime* rt, int k) {
  const double t = kFirst + 0.001 * k;
  const double identity[4] = {1, 0, 0, 0}, fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1};
  const chladni_object object{object_id(k % kObjects)};
  const double x = k % kObjects - 1.5;
  chladni_status s = CHLADNI_QUEUE_FULL;
  while (s == CHLADNI_QUEUE_FULL) {
    switch (k % 4) {
      case 0: {
        chladni_impact im{};
        im.object = object;
        im.time = t;
        im.impulse = 0.005 + 0.001 * (k % 7);
        im.direction[2] = -1;
        im.vertex = -1;
        im.contact_time = k % 8 ? 0.0 : 0.0007;
        s = chladni_impact_post(rt, &im);
        break;
      }
      case 1: {
        const double at[3] = {x, 2.0 + 0.001 * k, 0.0};
        s = chladni_object_move(rt, object, t, at, identity);
        break;
      }
      case 2: {
        const double pos[3] = {0.0005 * k, 0, 0};
        s = chladni_listener_set(rt, t, pos, fwd, up);
        break;
      }
      default:
        s = chladni_shaker_shake(rt, chladni_shaker{object_id(0)}, t, 0.3);
    }
    if (s == CHLADNI_QUEUE_FULL) std::this_thread::yield();
  }
  EXPECT_EQ(s, CHLADNI_OK) << chladni_last_error();
}

}  // namespace

TEST(Threads, GameThreadPostsWhileTheAudioThreadRenders) {
  // Reference: everything posted before the first render, one thread.
  chladni_runtime* ref_rt = make_runtime();
  for (int k = 0; k < kCommands; ++k) post(ref_rt, k);
  std::vector<float> ref(2 * kBlock * kBlocks);
  for (int b = 0; b < kBlocks; ++b)
    ASSERT_EQ(chladni_runtime_render(ref_rt, ref.data() + 2 * kBlock * b, kBlock), CHLADNI_OK);
  chladni_runtime_destroy(ref_rt);

  // The same commands from a game thread while the audio thread renders the first second; the
  // audio thread goes past kFirst only once every command is in (they are all for later), so
  // the result must not depend on the interleaving.
  chladni_runtime* rt = make_runtime();
  std::atomic<bool> posted{false};
  std::atomic<double> seen{0};
  std::thread game([&] {
    for (int k = 0; k < kCommands; ++k) {
      post(rt, k);
      seen.store(
          std::max(seen.load(), chladni_runtime_time(rt)));  // the clock, read across threads
    }
    posted.store(true, std::memory_order_release);
  });
  std::vector<float> out(ref.size());
  const int before = static_cast<int>(kFirst * 48000 / kBlock);
  for (int b = 0; b < kBlocks; ++b) {
    if (b == before)
      while (!posted.load(std::memory_order_acquire)) std::this_thread::yield();
    ASSERT_EQ(chladni_runtime_render(rt, out.data() + 2 * kBlock * b, kBlock), CHLADNI_OK)
        << chladni_last_error();
  }
  game.join();
  EXPECT_LE(seen.load(), kBlocks * double(kBlock) / 48000);
  chladni_runtime_destroy(rt);
  const double peak = max_abs(ref);
  ASSERT_GT(peak, 1e-4);
  double diff = 0;
  for (std::size_t i = 0; i < ref.size(); ++i)
    diff = std::max(diff, double(std::abs(ref[i] - out[i])));
  EXPECT_LE(diff, 1e-6 * peak);
}

TEST(Threads, FilterbankWorkersGiveTheSamplesOfOneThread) {
  // 3000 modes over two threads against one, with kicks and a gain change in every block.
  auto run = [](int threads) {
    CpuFilterbank fb({.capacity = 4096, .channels = 2, .threads = threads, .max_frames = 512});
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    for (uint32_t s = 0; s < 3000; ++s) {
      const float g[2] = {float(u(rng)), float(u(rng))};
      fb.set_mode(s, pole(2 * std::numbers::pi * (50 + 15000 * u(rng)), 1 + 20 * u(rng), 48000), g);
    }
    fb.set_high_water(3000);
    std::vector<float> all, out(2 * 512);
    for (int b = 0; b < 40; ++b) {
      std::vector<Excitation> ex;
      for (int k = 0; k < 64; ++k)
        ex.push_back({uint32_t(u(rng) * 3000), uint32_t(u(rng) * 512), float(u(rng)), 0.0f});
      const float g[2] = {float(u(rng)), 0.5f};
      fb.set_gains(uint32_t(u(rng) * 3000), g);
      fb.process(ex, 512, out.data());
      all.insert(all.end(), out.begin(), out.end());
    }
    return all;
  };
  const auto one = run(1), two = run(2);
  ASSERT_GT(max_abs(one), 0.0);
  double diff = 0;
  for (std::size_t i = 0; i < one.size(); ++i)
    diff = std::max(diff, double(std::abs(one[i] - two[i])));
  EXPECT_LE(diff, 1e-5 * max_abs(one));
}

TEST(Threads, ShakerExcitationOnWorkersGivesTheSamplesOfOneThread) {
  auto run = [](int threads) {
    CpuFilterbank fb({.capacity = 256, .channels = 1, .threads = 1});
    ShakerBank bank(fb, {.sample_rate = 48000, .max_voices = 8, .seed = 3, .threads = threads});
    const char* names[] = {"maraca", "tambourine", "gravel", "coins"};
    for (int v = 0; v < 8; ++v)
      bank.add_voice(instrument_voice(phisem_preset(names[v % 4]), 48000));
    std::vector<float> all, out(512);
    for (int b = 0; b < 60; ++b) {
      for (int v = 0; v < 8; ++v)
        if ((b + v) % 6 == 0) bank.shake(v, 0.6f, uint32_t(37 * v));
      bank.render(512, out.data());
      all.insert(all.end(), out.begin(), out.end());
    }
    return all;
  };
  const auto one = run(1), two = run(2);
  ASSERT_GT(max_abs(one), 0.0);
  for (std::size_t i = 0; i < one.size(); ++i) ASSERT_EQ(one[i], two[i]) << "sample " << i;
}

TEST(Threads, ObjectsSpawnAndGoWhileTheAudioThreadRenders) {
  // A control thread spawns and removes about a thousand objects a second, loading banks and
  // releasing them while their objects still play, and adds and removes gravel in them; a game
  // thread strikes, moves and shakes the live ones; this thread renders. Nothing waits on anything,
  // and at the end every place and bank has been given back.
  chladni_runtime* rt = test::storm_runtime();
  ASSERT_NE(rt, nullptr) << chladni_last_error();
  test::CApiStorm storm(rt);
  storm.start();
  std::vector<float> out(2 * kBlock);
  double peak = 0;
  bool finite = true;
  const auto t0 = std::chrono::steady_clock::now();
  while (storm.spawned.load() < 1000 &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
    ASSERT_EQ(chladni_runtime_render(rt, out.data(), kBlock), CHLADNI_OK) << chladni_last_error();
    for (float x : out) finite = finite && std::isfinite(x);
    peak = std::max(peak, max_abs(out));
  }
  storm.stop();
  EXPECT_EQ(storm.unexpected, "");
  EXPECT_FALSE(storm.game_unexpected.load());
  EXPECT_GE(storm.spawned.load(), 1000);
  EXPECT_GE(storm.removed.load(), 900);
  EXPECT_GE(storm.released.load(), 19);
  EXPECT_GT(storm.impacts.load(), 100);
  EXPECT_GT(storm.moves.load(), 100);
  EXPECT_GE(storm.shakers_added.load(), 300);
  EXPECT_GE(storm.shakers_removed.load(), 20);
  EXPECT_GE(storm.contacts_added.load(), 20);
  EXPECT_GE(storm.contact_states.load(), 20);
  EXPECT_GT(storm.shaken.load(), 20);
  EXPECT_TRUE(finite);
  EXPECT_GT(peak, 0.0);
  // Removed, everything fades out within the gain ramp and is then silent.
  storm.clear();
  EXPECT_EQ(storm.unexpected, "");
  for (int b = 0; b < 3; ++b) ASSERT_EQ(chladni_runtime_render(rt, out.data(), kBlock), CHLADNI_OK);
  EXPECT_EQ(max_abs(out), 0.0);
  rt->reclaim();  // this thread is the control thread now
  EXPECT_TRUE(rt->banks.empty());
  EXPECT_EQ(rt->free_places.size(), 64u);
  EXPECT_EQ(rt->free_shaker_places.size(), 64u);
  EXPECT_EQ(rt->lost_returns, 0u);
  chladni_runtime_destroy(rt);
}

TEST(Threads, PaperFramesPostedWhileTheAudioThreadRenders) {
  // The control thread analyses and renders a crumpling sheet's frames, waiting for room when it
  // is half a second ahead, and removes it; the audio thread, paced at a few times real time,
  // mixes what it is handed and retires the sheet.
  test::CApiPaperSheet p;
  ASSERT_NE(p.sheet.id, 0u);
  std::atomic<bool> done{false}, gave_up{false};
  std::string unexpected;
  std::thread control([&] {
    for (std::uint32_t f = 0; f < p.anim.frame_count() && !gave_up.load();) {
      const chladni_status s = p.post(f);
      if (s == CHLADNI_OK) {
        ++f;
      } else if (s == CHLADNI_QUEUE_FULL) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      } else {
        unexpected = chladni_last_error();
        break;
      }
    }
    if (chladni_paper_remove(p.rt, p.sheet) != CHLADNI_OK) unexpected = chladni_last_error();
    done.store(true, std::memory_order_release);
  });
  std::vector<float> out(2 * 256);
  float peak = 0;
  const auto t0 = std::chrono::steady_clock::now();
  // Past the end, 2.3 s for what is buffered and the tail to play out.
  for (int after = 0; after < 400;) {
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(60)) break;
    ASSERT_EQ(chladni_runtime_render(p.rt, out.data(), 256), CHLADNI_OK) << chladni_last_error();
    for (float x : out) {
      ASSERT_TRUE(std::isfinite(x));
      peak = std::max(peak, std::abs(x));
    }
    if (done.load(std::memory_order_acquire)) ++after;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  gave_up.store(true);
  control.join();
  EXPECT_TRUE(done.load());
  EXPECT_EQ(unexpected, "");
  EXPECT_GT(peak, 0.0f);
  EXPECT_TRUE(p.place_given_back());
}
