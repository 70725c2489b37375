// No clicks: an impact's modes follow its contact force as it acts (the continuous solution,
// sampled), and gain changes ramp. Each test bounds the largest sample-to-sample jump against
// the slope a ringing mode of that level has anyway.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "chladni/core/scene.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/modal/synth.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {
constexpr double kFs = 48000;
constexpr double kPi = std::numbers::pi;

// Im of the state of a mode driven from t = 0 by a half-sine force of unit impulse lasting tau:
// integral_0^min(t, tau) F(s) exp(lambda (t - s)) ds, by a fine midpoint rule.
double reference(double t, double tau, double omega, double decay) {
  if (t <= 0) return 0.0;
  const std::complex<double> lambda(-decay, omega);
  const double upper = std::min(t, tau);
  const int n = 4000;
  std::complex<double> sum = 0.0;
  for (int k = 0; k < n; ++k) {
    const double s = (k + 0.5) * upper / n;
    sum += kPi / (2 * tau) * std::sin(kPi * s / tau) * std::exp(lambda * (t - s));
  }
  return (sum * (upper / n)).imag();
}

double largest_step(const std::vector<float>& y, std::size_t from = 1) {
  double m = 0;
  for (std::size_t n = std::max<std::size_t>(from, 1); n < y.size(); ++n)
    m = std::max(m, double(std::abs(y[n] - y[n - 1])));
  return m;
}
}  // namespace

TEST(Contact, ModesFollowTheContinuousSolutionThroughTheContact) {
  // 1 kHz is the contact's own frequency (pi / tau): the closed form's 0/0 case.
  const double tau = 0.0005;
  for (double hz : {150.0, 1000.0, 6000.0, 15000.0, 23000.0}) {
    CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
    Synth synth(fb, {.sample_rate = kFs});
    const ModeSpec m[] = {{2 * kPi * hz, 30.0, 1.0f}};
    const auto v = synth.start_voice(m);
    const std::complex<float> a[] = {{1.0f, 0.0f}};
    const double start = 10.3;  // between samples
    synth.strike(v, a, start, tau);
    std::vector<float> out(512);
    synth.render(256, out.data());
    synth.render(256, out.data() + 256);
    double peak = 0, err = 0;
    for (std::size_t n = 0; n < out.size(); ++n) {
      const double ref = reference((n - start) / kFs, tau, 2 * kPi * hz, 30.0);
      peak = std::max(peak, std::abs(ref));
      err = std::max(err, std::abs(out[n] - ref));
    }
    EXPECT_LT(err, 2e-5 * peak) << hz << " Hz: peak " << peak;
    EXPECT_EQ(out[10], 0.0f) << "before the contact starts";
  }
}

TEST(Contact, OnsetBuildsUpFromZeroWithoutAStep) {
  // A 1 kHz mode struck with a 0.5 ms contact: the state that is right after the contact would
  // jump in at once (about 79 % of the peak); the force builds it up over 24 samples.
  const double hz = 1000, tau = 0.0005;
  CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
  Synth synth(fb, {.sample_rate = kFs});
  const ModeSpec m[] = {{2 * kPi * hz, 5.0, 1.0f}};
  const auto v = synth.start_voice(m);
  const std::complex<float> a[] = {{1.0f, 0.0f}};
  synth.strike(v, a, 100.0, tau);
  std::vector<float> out(1024);
  synth.render(1024, out.data());
  const double peak = test::max_abs(out);
  EXPECT_LT(std::abs(out[101]), 0.02 * peak);
  // A free sinusoid of this peak moves at most 2 sin(omega T / 2) peak per sample.
  const double slope = 2 * std::sin(kPi * hz / kFs) * peak;
  EXPECT_LT(largest_step(out), 1.01 * slope);
  EXPECT_EQ(synth.stats().contacts_undriven, 0u);
}

TEST(Contact, SpansRendersAndSharesItsStorage) {
  // A 3 ms contact over renders of 16 frames, many impacts at once, and more than the storage
  // holds: every render's output equals one long render's, and overflowing contacts are counted.
  const double tau = 0.003;
  auto run = [&](uint32_t block, uint32_t max_contact_modes) {
    CpuFilterbank fb({.capacity = 1024, .channels = 2, .threads = 1});
    Synth synth(fb, {.sample_rate = kFs, .max_contact_modes = max_contact_modes});
    std::vector<ModeSpec> modes;
    for (int i = 0; i < 40; ++i) modes.push_back({2 * kPi * (200 + 97 * i), 3.0 + i, 0.5f});
    const auto v = synth.start_voice(modes);
    synth.set_pan(v, 0.8f, 0.6f);
    std::vector<std::complex<float>> a(modes.size(), {1.0f, 0.0f});
    std::vector<float> out;
    std::vector<float> buf(block * 2);
    for (uint64_t t = 0; t < 4096; t += block) {
      for (int k = 0; k < 6; ++k) {  // impacts at 100.25 + 90 k: contacts overlap
        const double at = 100.25 + 90.0 * k;
        if (at >= double(t) - 1 && std::ceil(at) < double(t + block))
          synth.strike(v, a, at - double(t), tau);
      }
      synth.render(block, buf.data());
      out.insert(out.end(), buf.begin(), buf.end());
    }
    return std::pair(out, synth.stats().contacts_undriven);
  };
  const auto [whole, none] = run(4096, 1u << 15);
  const auto [pieces, none2] = run(16, 1u << 15);
  EXPECT_EQ(none, 0u);
  EXPECT_EQ(none2, 0u);
  EXPECT_LT(test::max_diff(whole, pieces), 1e-5 * test::max_abs(whole));
  // Room for one contact's 40 modes and a half: the overlapping ones go undriven.
  const auto [tight, undriven] = run(16, 60);
  EXPECT_GT(undriven, 0u);
  EXPECT_LT(largest_step(tight), 10 * largest_step(whole));  // still no runaway
}

namespace {

constexpr double kModeHz = 700;

// One stereo object with one mode (so that its slope is known), struck twice (an ideal impulse,
// then a 1 ms contact), heard by a listener who walks from 2 m to 0.3 m (17 dB louder) while the
// object crosses from the listener's left to the right.
Scene moving_scene() {
  Scene s;
  s.channels = 2;
  s.duration = 1.2;
  SceneObject o;
  o.name = "bowl";
  o.position = {-0.5, 2, 0};
  o.modes = {{kModeHz, 2.0, 0.02}};
  s.objects = {o};
  ImpactEvent a;
  a.time = 0.05;
  a.impulse = 0.01;
  ImpactEvent b = a;
  b.time = 0.3000123;
  b.contact_time = 0.001;
  s.events = {a, b};
  MoveEvent walk;
  walk.time = 0.5;
  walk.position = Vec3{0, 1.7, 0};
  MoveEvent cross;
  cross.time = 0.8;
  cross.object = 0;
  cross.position = Vec3{0.5, 2, 0};
  s.moves = {walk, cross};
  return s;
}

// Largest step from 2 ms before `at` to 8 ms after, over the largest step a free mode of the
// window's peak level makes (2 sin(omega T / 2) peak): at most about 1 when nothing clicks.
double step_ratio(const AudioBuffer& audio, double at) {
  const int ch = audio.channels;
  const auto n0 = static_cast<std::size_t>((at - 0.002) * kFs);
  const auto n1 = static_cast<std::size_t>((at + 0.008) * kFs);
  double worst = 0;
  for (int c = 0; c < ch; ++c) {
    double peak = 0, step = 0;
    for (std::size_t n = n0; n < n1; ++n) {
      const float y = audio.samples[n * ch + c], prev = audio.samples[(n - 1) * ch + c];
      peak = std::max(peak, double(std::abs(y)));
      step = std::max(step, double(std::abs(y - prev)));
    }
    worst = std::max(worst, step / (2 * std::sin(kPi * kModeHz / kFs) * peak));
  }
  return worst;
}

AudioBuffer render_moving(Filterbank& fb) {
  const Scene scene = moving_scene();
  std::vector<ObjectModes> objects{object_modes(scene.objects[0].modes)};
  return render_scene(scene, objects, fb, RenderOptions{});
}

}  // namespace

TEST(Clicks, NoEventStepsFasterThanTheSoundItself) {
  std::vector<std::unique_ptr<Filterbank>> backends;
  backends.push_back(std::make_unique<CpuFilterbank>(
      CpuFilterbankOptions{.capacity = 256, .channels = 2, .threads = 1}));
  if (auto ctx = test::gpu_context())
    backends.push_back(
        std::make_unique<GpuFilterbank>(ctx, GpuFilterbankOptions{.capacity = 256, .channels = 2}));
  for (auto& fb : backends) {
    SCOPED_TRACE(fb->name());
    const AudioBuffer audio = render_moving(*fb);
    for (double at : {0.05, 0.3000123, 0.5, 0.8})
      EXPECT_LT(step_ratio(audio, at), 1.05) << "event at " << at << " s";
  }
  // The same scene with gains that change at once: the listener's step and the crossing click.
  CpuFilterbank abrupt({.capacity = 256, .channels = 2, .threads = 1, .gain_ramp = 0});
  const AudioBuffer audio = render_moving(abrupt);
  EXPECT_GT(step_ratio(audio, 0.5), 3.0);
  EXPECT_GT(step_ratio(audio, 0.8), 3.0);
}
