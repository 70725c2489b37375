// Voices: retirement at -100 dB, slot reuse, stealing of the least audible modes, block-size
// independence of rendered scenes, and no allocation on the audio path.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/modal/synth.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {
constexpr double kSynthRate = 48000;
ModeSpec mode(double hz, double decay, float gain = 1) {
  return {2 * std::numbers::pi * hz, decay, gain};
}
}  // namespace

TEST(Synth, RetiresAModeOnce100dBBelowItsPeak) {
  CpuFilterbank fb({.capacity = 256, .channels = 1, .threads = 1});
  Synth synth(fb, {.sample_rate = kSynthRate});
  const ModeSpec m[] = {mode(300, 10.0)};
  const auto v = synth.start_voice(m);
  const std::complex<float> a[] = {{1.0f, 0.0f}};
  synth.excite(v, a, 0);
  EXPECT_EQ(synth.active_modes(), 1u);
  // exp(-10 t) = 1e-5 at t = ln(1e5) / 10 = 1.151 s.
  std::vector<float> out(256);
  const uint64_t retire = static_cast<uint64_t>(std::log(1e5) / 10.0 * kSynthRate);
  while (synth.time() + 256 < retire) {
    synth.render(256, out.data());
    ASSERT_EQ(synth.active_modes(), 1u) << "retired early at sample " << synth.time();
  }
  for (int i = 0; i < 3; ++i) synth.render(256, out.data());
  EXPECT_EQ(synth.active_modes(), 0u);
  EXPECT_EQ(synth.stats().retired, 1u);
  EXPECT_EQ(synth.slot_of(v, 0), -1);
  // A new kick makes it resident again, in the lowest slot.
  synth.excite(v, a, 0);
  EXPECT_EQ(synth.slot_of(v, 0), 0);
}

// Users of one filterbank lease disjoint slot ranges; a synth sounds the same in any range, and
// the processed range covers every lease in use.
TEST(Synth, LeasedSlotRangesShareAFilterbankWithoutChangingTheSound) {
  const ModeSpec m[] = {mode(440, 3.0), mode(1250, 8.0, 0.5f), mode(3100, 20.0, 0.25f)};
  const std::complex<float> a[] = {{1.0f, 0.0f}, {0.0f, 0.7f}, {0.3f, 0.2f}};
  auto run = [&](Filterbank& fb, Synth& synth) {
    const auto v = synth.start_voice(m);
    synth.excite(v, a, 17);
    std::vector<float> out(4 * 256), block(256);
    for (int b = 0; b < 4; ++b) {
      synth.render(256, block.data());
      std::copy(block.begin(), block.end(), out.begin() + 256 * b);
    }
    (void)fb;
    return out;
  };
  CpuFilterbank alone({.capacity = 64, .channels = 1, .threads = 1});
  Synth first(alone, {.sample_rate = kSynthRate});
  const auto reference = run(alone, first);

  CpuFilterbank shared({.capacity = 64, .channels = 1, .threads = 1});
  ShakerBank shakers(shared, {.sample_rate = kSynthRate, .slots = 24, .max_voices = 2});
  EXPECT_EQ(shared.unleased(), 40u);
  Synth second(shared, {.sample_rate = kSynthRate, .max_modes = 32});
  EXPECT_EQ(shared.unleased(), 8u);
  EXPECT_THROW(shared.lease(9), InputError);
  EXPECT_EQ(shared.lease(8).begin, 56u);
  EXPECT_THROW(Synth(shared, {.sample_rate = kSynthRate}), InputError);  // nothing left to lease
  const auto out = run(shared, second);
  ASSERT_EQ(out.size(), reference.size());
  for (std::size_t i = 0; i < out.size(); ++i) ASSERT_EQ(out[i], reference[i]) << "sample " << i;
  // The synth's modes sit above the shakers' slots.
  const auto v = second.start_voice(m);
  second.excite(v, a, 0);
  EXPECT_GE(second.slot_of(v, 0), 24);
  EXPECT_LT(second.slot_of(v, 2), 24 + 32);
  // A shaker voice in its lease sounds alongside the synth (its slots are processed).
  shakers.add_voice(instrument_voice(phisem_preset("maraca"), kSynthRate));
  ASSERT_TRUE(shakers.shake(0, 1.0f, 0));
  std::vector<float> block(256);
  const DriveInput in = shakers.prepare(256);
  second.render(256, block.data(), in);
  shakers.finish(256);
  double shaker_state = 0;
  for (uint32_t s = 0; s < 24; ++s) shaker_state += std::abs(shared.state(s));
  EXPECT_GT(shaker_state, 0.0);
}

// A filterbank outlives its users: a synth's lease returns when it goes, its ringing slots
// cleared, so the next user starts from silence.
TEST(Synth, ALeaseReturnsWithItsSlotsSilenced) {
  CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
  std::vector<float> out(256);
  {
    Synth first(fb, {.sample_rate = kSynthRate});
    EXPECT_EQ(fb.unleased(), 0u);
    const ModeSpec m[] = {mode(440, 0.5)};
    const std::complex<float> a[] = {{1.0f, 0.0f}};
    first.excite(first.start_voice(m), a, 0);
    first.render(256, out.data());
    ASSERT_GT(test::max_abs(out), 0.1);
  }
  EXPECT_EQ(fb.unleased(), 64u);
  Synth second(fb, {.sample_rate = kSynthRate});
  second.render(256, out.data());
  EXPECT_EQ(test::max_abs(out), 0.0);
  EXPECT_EQ(fb.state(0), std::complex<float>(0, 0));
}

TEST(Synth, StealsTheLeastAudibleModesWhenTheBudgetIsFull) {
  CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
  Synth synth(fb, {.sample_rate = kSynthRate, .max_modes = 8});
  std::vector<ModeSpec> a_modes, b_modes;
  std::vector<std::complex<float>> a_amp, b_amp;
  for (int i = 0; i < 8; ++i) {
    a_modes.push_back(mode(200 + 100 * i, 1.0));
    a_amp.push_back({std::pow(0.5f, float(i)), 0.0f});  // mode i is 6 dB quieter than i - 1
  }
  for (int i = 0; i < 3; ++i) {
    b_modes.push_back(mode(5000 + 100 * i, 1.0));
    b_amp.push_back({1.0f, 0.0f});
  }
  const auto a = synth.start_voice(a_modes), b = synth.start_voice(b_modes);
  synth.excite(a, a_amp, 0);
  std::vector<float> out(256);
  synth.render(256, out.data());
  EXPECT_EQ(synth.active_modes(), 8u);
  synth.excite(b, b_amp, 0);
  EXPECT_EQ(synth.active_modes(), 8u);
  EXPECT_EQ(synth.stats().stolen, 3u);
  for (int i = 0; i < 5; ++i)
    EXPECT_GE(synth.slot_of(a, i), 0) << "loud mode " << i << " was stolen";
  for (int i = 5; i < 8; ++i) EXPECT_EQ(synth.slot_of(a, i), -1) << "quiet mode " << i << " kept";
  for (int i = 0; i < 3; ++i) EXPECT_GE(synth.slot_of(b, i), 0);
}

TEST(Synth, StopVoiceFreesItsSlotsAndDropsPendingKicks) {
  CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
  Synth synth(fb, {.sample_rate = kSynthRate});
  const ModeSpec m[] = {mode(440, 1.0), mode(880, 1.0)};
  const auto v = synth.start_voice(m);
  const std::complex<float> amp[] = {{1, 0}, {1, 0}};
  synth.excite(v, amp, 10);
  synth.stop_voice(v);
  EXPECT_EQ(synth.active_modes(), 0u);
  EXPECT_EQ(synth.pending_excitations(), 0u);
  std::vector<float> out(256);
  synth.render(256, out.data());
  for (float x : out) EXPECT_EQ(x, 0.0f);
  EXPECT_THROW(synth.excite(v, amp, 0), std::invalid_argument);
}

TEST(Synth, RejectsNonFiniteInput) {
  CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
  Synth synth(fb, {.sample_rate = kSynthRate});
  const ModeSpec bad[] = {{NAN, 1.0, 1.0f}};
  EXPECT_THROW(synth.start_voice(bad), InputError);
  const ModeSpec m[] = {mode(440, 1.0)};
  const auto v = synth.start_voice(m);
  const std::complex<float> amp[] = {{INFINITY, 0}};
  EXPECT_THROW(synth.excite(v, amp, 0), InputError);
}

namespace {

Scene test_scene(int channels) {
  Scene s;
  s.channels = channels;
  s.duration = 2.0;
  SceneObject a;
  a.name = "a";
  a.position = {-1, 1, 0};
  for (int i = 0; i < 300; ++i)
    a.modes.push_back({100.0 + 53.0 * i, 2.0 + i % 11, 0.01 * (1 + i % 5)});
  SceneObject b = a;
  b.name = "b";
  b.position = {2, 0.5, 0};
  s.objects = {a, b};
  for (int k = 0; k < 12; ++k) {
    ImpactEvent e;
    e.time = 0.01 + 0.137 * k;  // not on block boundaries
    e.object = k % 2;
    e.impulse = 0.01 * (1 + k % 3);
    e.contact_time = k % 4 == 0 ? 0.0005 : 0.0;
    s.events.push_back(e);
  }
  return s;
}

AudioBuffer render_with(Filterbank& fb, const Scene& scene, uint32_t block) {
  std::vector<ObjectModes> objects;
  for (const SceneObject& o : scene.objects) objects.push_back(object_modes(o.modes));
  RenderOptions ro;
  ro.block = block;
  return render_scene(scene, objects, fb, ro);
}

}  // namespace

TEST(Render, OutputDoesNotDependOnBlockSize) {
  const Scene scene = test_scene(2);
  CpuFilterbank fb256({.capacity = 1024, .channels = 2, .threads = 2});
  const AudioBuffer ref = render_with(fb256, scene, 256);
  ASSERT_GT(test::max_abs(ref.samples), 1e-3);
  for (uint32_t block : {64u, 100u, 1000u}) {
    CpuFilterbank fb({.capacity = 1024, .channels = 2, .threads = 2});
    EXPECT_LT(test::max_diff(ref.samples, render_with(fb, scene, block).samples),
              1e-5 * test::max_abs(ref.samples))
        << "block " << block;
  }
  if (auto ctx = test::gpu_context()) {
    GpuFilterbank gpu(ctx, {.capacity = 1024, .channels = 2});
    EXPECT_LT(test::max_diff(ref.samples, render_with(gpu, scene, 1000).samples),
              1e-4 * test::max_abs(ref.samples))
        << "gpu, block 1000";
  }
}

TEST(Render, PanFollowsTheObjectsSide) {
  Scene scene = test_scene(2);
  scene.events.resize(1);  // one hit on object a, on the listener's left (x < 0)
  CpuFilterbank fb({.capacity = 1024, .channels = 2, .threads = 1});
  const AudioBuffer out = render_with(fb, scene, 256);
  double l = 0, r = 0;
  for (std::size_t i = 0; i < out.frames(); ++i) {
    l += double(out.samples[2 * i]) * out.samples[2 * i];
    r += double(out.samples[2 * i + 1]) * out.samples[2 * i + 1];
  }
  EXPECT_GT(l, 4 * r);  // 45 degrees left: cos^2/sin^2 of 22.5 degrees ~ 5.8
}

TEST(Render, SubSampleEventTimeShiftsPhaseExactly) {
  // One undamped-ish mode hit at t = 0.5 / fs must equal the analytic sine delayed by half a
  // sample.
  Scene s;
  s.channels = 1;
  s.duration = 0.05;
  SceneObject o;
  o.name = "o";
  o.position = {0, 1, 0};  // 1 m: unit gain
  o.modes = {{1000.0, 1.0, 1.0}};
  s.objects = {o};
  ImpactEvent e;
  e.time = 0.5 / kSynthRate;
  e.impulse = 1.0;
  s.events = {e};
  CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
  const AudioBuffer out = render_with(fb, s, 256);
  const double w = 2 * std::numbers::pi * 1000.0;
  for (std::size_t n = 1; n < out.frames(); ++n) {
    const double t = n / kSynthRate - e.time;
    EXPECT_NEAR(out.samples[n], std::exp(-t) * std::sin(w * t), 1e-4) << n;
  }
}
