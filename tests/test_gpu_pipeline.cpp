// The pipelined GPU filterbank: process() returns without waiting for the device and hands back
// the samples of the waiting filterbank exactly max_frames() later, whatever the calls do in
// between (slot updates, gain ramps, retuning, driven inputs, state reads, short blocks); and
// the C API on it sounds as the CPU backend does, one block later, contact forces included.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "chladni/chladni.h"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::runtime;
using chladni::test::max_abs;

namespace {

constexpr uint32_t kMaxFrames = 256;

struct NoStage : GpuInputStage {
  void record(gpu::Sequence&, uint32_t) override {}
};

// A scripted run of varying block sizes, the same for every filterbank it is given.
std::vector<float> scripted_run(GpuFilterbank& fb, std::vector<std::complex<float>>* states) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  const uint32_t modes = 1500;
  for (uint32_t s = 0; s < modes; ++s) {
    const float g[2] = {float(u(rng)), float(u(rng))};
    fb.set_mode(s, pole(2 * std::numbers::pi * (60 + 12000 * u(rng)), 2 + 30 * u(rng), 48000), g);
  }
  for (uint32_t s = 0; s < 8; ++s) fb.set_input(s, s % 2, {0.3f, 0.1f});
  fb.set_high_water(modes);
  const uint32_t sizes[] = {256, 100, 37, 256, 200, 1, 256, 129};
  std::vector<float> all, out(2 * kMaxFrames), drive(2 * kMaxFrames);
  for (int b = 0; b < 64; ++b) {
    const uint32_t frames = sizes[b % 8];
    std::vector<Excitation> ex;
    for (int k = 0; k < 20; ++k)
      ex.push_back({uint32_t(u(rng) * modes), uint32_t(u(rng) * frames), float(u(rng)), 0.2f});
    for (float& x : drive) x = float(u(rng) - 0.5);
    if (b % 3 == 0) {
      const float g[2] = {float(u(rng)), float(u(rng))};
      fb.set_gains(uint32_t(u(rng) * modes), g);  // ramps across the next calls
    }
    if (b % 5 == 0)
      fb.set_pole(uint32_t(u(rng) * modes), pole(2 * std::numbers::pi * 900, 4, 48000));
    const float fresh[2] = {0.5f, 0.25f};
    if (b % 7 == 0) fb.set_mode(uint32_t(u(rng) * modes), pole(3000, 1, 48000), fresh);
    // Rows of `frames` samples per stream, as the filterbank reads them.
    std::vector<float> rows(2 * frames);
    for (uint32_t i = 0; i < 2 * frames; ++i) rows[i] = drive[i];
    fb.process(ex, frames, out.data(), DriveInput{rows.data(), 2});
    all.insert(all.end(), out.begin(), out.begin() + 2 * frames);
    if (b == 40) states->push_back(fb.state(3));
  }
  return all;
}

}  // namespace

TEST(GpuPipeline, HandsBackTheWaitingFilterbanksSamplesOneBlockLate) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  GpuFilterbank waiting(
      ctx, {.capacity = 2048, .channels = 2, .max_frames = kMaxFrames, .max_streams = 2});
  GpuFilterbank pipelined(ctx, {.capacity = 2048,
                                .channels = 2,
                                .max_frames = kMaxFrames,
                                .max_streams = 2,
                                .pipelined = true});
  EXPECT_EQ(waiting.latency(), 0u);
  EXPECT_EQ(pipelined.latency(), kMaxFrames);
  NoStage stage;
  EXPECT_THROW(pipelined.set_input_stage(&stage), std::invalid_argument);
  std::vector<std::complex<float>> s1, s2;
  const auto p = scripted_run(waiting, &s1);
  const auto q = scripted_run(pipelined, &s2);
  ASSERT_EQ(p.size(), q.size());
  const std::size_t lag = 2 * kMaxFrames;
  EXPECT_EQ(max_abs(std::span(q).first(lag)), 0.0);
  const double peak = max_abs(p);
  ASSERT_GT(peak, 0.01);
  double diff = 0;
  for (std::size_t i = 0; i + lag < q.size(); ++i)
    diff = std::max(diff, double(std::abs(q[i + lag] - p[i])));
  EXPECT_LE(diff, 1e-6 * peak);
  ASSERT_EQ(s1.size(), 1u);
  EXPECT_EQ(s1, s2);  // a state read waits for the block in flight
  EXPECT_EQ(ctx->validation_errors(), 0u);
}

TEST(GpuPipeline, CApiSoundsAsTheCpuBackendOneBlockLater) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  auto run = [](chladni_backend backend, double* latency) {
    chladni_config c;
    chladni_config_default(&c);
    c.backend = backend;
    c.threads = 1;
    c.mode_budget = 4096;
    chladni_runtime* rt = nullptr;
    EXPECT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_OK) << chladni_last_error();
    const double hz[] = {441, 1142, 2650, 5210}, decay[] = {2, 3, 5, 9},
                 amp[] = {0.02, 0.01, 0.004, 0.002};
    chladni_bank bank = {0};
    EXPECT_EQ(chladni_bank_from_modes(rt, hz, decay, amp, 4, &bank), CHLADNI_OK);
    const double at[3] = {0.3, 1, 0}, identity[4] = {1, 0, 0, 0}, fwd[3] = {0, 1, 0},
                 up[3] = {0, 0, 1}, near[3] = {0.1, 0.5, 0};
    chladni_object id{0};
    chladni_shaker shaker{0};
    EXPECT_EQ(chladni_object_spawn(rt, bank, at, identity, 1.0, &id), CHLADNI_OK);
    const chladni_shaker_desc gravel{id, "gravel", 0, 1, 0};
    EXPECT_EQ(chladni_shaker_add(rt, &gravel, &shaker), CHLADNI_OK) << chladni_last_error();
    for (int k = 0; k < 6; ++k) {
      chladni_impact im{};
      im.object = id;
      im.time = 0.013 + 0.061 * k;
      im.impulse = 0.01;
      im.direction[2] = -1;
      im.vertex = -1;
      im.contact_time = k % 2 ? 0.002 : 0.0;  // contact forces are added on the host
      EXPECT_EQ(chladni_impact_post(rt, &im), CHLADNI_OK);
    }
    EXPECT_EQ(chladni_shaker_shake(rt, shaker, 0.2, 0.6), CHLADNI_OK);
    EXPECT_EQ(chladni_listener_set(rt, 0.25, near, fwd, up), CHLADNI_OK);
    std::vector<float> out(2 * 48000 / 2);
    for (std::size_t n = 0; n < out.size() / 2; n += 480)
      EXPECT_EQ(chladni_runtime_render(rt, out.data() + 2 * n, 480), CHLADNI_OK)
          << chladni_last_error();
    *latency = chladni_runtime_latency(rt);
    chladni_runtime_destroy(rt);
    return out;
  };
  double cpu_latency = -1, gpu_latency = -1;
  const auto cpu = run(CHLADNI_BACKEND_CPU, &cpu_latency);
  const auto gpu = run(CHLADNI_BACKEND_GPU, &gpu_latency);
  EXPECT_EQ(cpu_latency, 0.0);
  EXPECT_DOUBLE_EQ(gpu_latency, 256.0 / 48000);
  const std::size_t lag = 2 * 256;
  EXPECT_EQ(max_abs(std::span(gpu).first(lag)), 0.0);
  const double peak = max_abs(cpu);
  ASSERT_GT(peak, 1e-4);
  double diff = 0;
  for (std::size_t i = 0; i + lag < gpu.size(); ++i)
    diff = std::max(diff, double(std::abs(gpu[i + lag] - cpu[i])));
  EXPECT_LT(diff, 1e-4 * peak);
}
