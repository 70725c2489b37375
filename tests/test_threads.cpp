// The runtime's multi-threaded paths: a game thread posting through the C API's queue while the
// audio thread renders, the CPU filterbank's worker threads and the shakers' excitation threads.
// Each gives the samples of its single-threaded run. CI also runs these under ThreadSanitizer
// (scripts/tsan.sh), which fails them on any data race.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

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
  chladni_bank* bank = nullptr;
  EXPECT_EQ(chladni_bank_from_modes(rt, hz.data(), decay.data(), amp.data(), hz.size(), &bank),
            CHLADNI_OK);
  const double identity[4] = {1, 0, 0, 0};
  for (int k = 0; k < kObjects; ++k) {
    const double at[3] = {k - 1.5, 2.0, 0.0};
    uint32_t id = 0;
    EXPECT_EQ(chladni_spawn(rt, bank, at, identity, 1.0, &id), CHLADNI_OK);
  }
  const chladni_shaker_desc gravel{0, "gravel", 0, 1, 0};
  uint32_t shaker = 0;
  EXPECT_EQ(chladni_shaker_add(rt, &gravel, &shaker), CHLADNI_OK) << chladni_last_error();
  return rt;
}

// Command k: an impact, a move, a listener step or a shake, at kFirst + k ms. Retries while the
// queue is full (the audio thread drains it).
void post(chladni_runtime* rt, int k) {
  const double t = kFirst + 0.001 * k;
  const double identity[4] = {1, 0, 0, 0}, fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1};
  const uint32_t object = static_cast<uint32_t>(k % kObjects);
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
        s = chladni_post_impact(rt, &im);
        break;
      }
      case 1: {
        const double at[3] = {object - 1.5, 2.0 + 0.001 * k, 0.0};
        s = chladni_post_move(rt, object, t, at, identity);
        break;
      }
      case 2: {
        const double pos[3] = {0.0005 * k, 0, 0};
        s = chladni_post_listener(rt, t, pos, fwd, up);
        break;
      }
      default:
        s = chladni_post_shake(rt, 0, t, 0.3);
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
    ASSERT_EQ(chladni_render(ref_rt, ref.data() + 2 * kBlock * b, kBlock), CHLADNI_OK);
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
      seen.store(std::max(seen.load(), chladni_time(rt)));  // the clock, read across threads
    }
    posted.store(true, std::memory_order_release);
  });
  std::vector<float> out(ref.size());
  const int before = static_cast<int>(kFirst * 48000 / kBlock);
  for (int b = 0; b < kBlocks; ++b) {
    if (b == before)
      while (!posted.load(std::memory_order_acquire)) std::this_thread::yield();
    ASSERT_EQ(chladni_render(rt, out.data() + 2 * kBlock * b, kBlock), CHLADNI_OK)
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
