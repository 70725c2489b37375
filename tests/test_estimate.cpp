// Estimation from recordings: features of known partials, the damping curve, the material fit
// (a bar rendered by the runtime from known parameters, then recovered), the real recordings'
// partials, and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "chladni/core/analytic_bar.hpp"
#include "chladni/core/audio_file.hpp"
#include "chladni/core/error.hpp"
#include "chladni/estimate/damping_fit.hpp"
#include "chladni/estimate/features.hpp"
#include "chladni/estimate/material_fit.hpp"
#include "chladni/estimate/recording.hpp"
#include "chladni/estimate/struck_modes.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "test_support.hpp"

namespace chladni {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// A 0.9 m bar (bending modes from 64 Hz at steel) of `E`, struck at x = 0.17 m with a 0.3 ms
// contact and heard 1 m above, through the runtime; white noise at `snr_db` below the sound's
// rms over its first second.
struct Rendered {
  std::vector<double> x;
  double fs = 48000;
  BarSpec bar;
  Vec3 point{0.17, 0.015, 0.01}, listener{0.17, 0.015, 1.01};
};

Rendered render_bar(double E, const DampingModel& damping, double snr_db, uint32_t seed = 7) {
  Rendered r;
  r.bar.length = 0.9;
  r.bar.youngs_modulus = E;
  r.bar.damping = damping;
  Scene scene;
  scene.sample_rate = int(r.fs);
  scene.channels = 1;
  scene.duration = 2.5;
  scene.listener.position = r.listener;
  SceneObject obj;
  obj.name = "bar";
  obj.source = SceneObject::Source::Bar;
  obj.bar = r.bar;
  scene.objects = {obj};
  ImpactEvent e;
  e.time = 0.02;
  e.impulse = 0.01;
  e.point = r.point;
  e.contact_time = 3e-4;
  scene.events = {e};
  auto playable = runtime::resolve_objects(scene);
  std::vector<runtime::ObjectModes> objects{playable[0].modes};
  runtime::CpuFilterbank fb({.capacity = 4096, .channels = 1, .threads = 1});
  const AudioBuffer out = runtime::render_scene(scene, objects, fb, {});
  r.x.assign(out.samples.begin(), out.samples.end());
  if (std::isfinite(snr_db)) {
    double rms = 0;
    const std::size_t n = std::min<std::size_t>(r.x.size(), std::size_t(r.fs));
    for (std::size_t i = 0; i < n; ++i) rms += r.x[i] * r.x[i];
    rms = std::sqrt(rms / double(n));
    std::mt19937 gen(seed);
    std::normal_distribution<double> noise(0.0, rms * std::pow(10.0, -snr_db / 20));
    for (double& v : r.x) v += noise(gen);
  }
  return r;
}

// Largest relative difference of two damping curves over [lo, hi] Hz.
double curve_error(const DampingModel& a, const DampingModel& b, double lo, double hi) {
  double worst = 0;
  for (int i = 0; i <= 40; ++i) {
    const double w = kTwoPi * lo * std::pow(hi / lo, i / 40.0);
    worst = std::max(worst, std::abs(a.coefficient(w) / b.coefficient(w) - 1));
  }
  return worst;
}

TEST(EstimateFeatures, FindsKnownPartialsAndTheirDecays) {
  const double fs = 44100;
  std::vector<estimate::Feature> truth = {{220, 3.0, 0.5, 0.3},    {587.3, 9.0, 0.2, 1.0},
                                          {1310, 2.0, 0.1, -2.0},  {2950, 25.0, 0.3, 0.5},
                                          {6021, 14.0, 0.05, 2.5}, {11800, 60.0, 0.08, -1.0}};
  std::vector<double> x(std::size_t(1.5 * fs), 0.0);
  std::vector<double> y = estimate::synthesize(truth, fs, x.size() - 100);
  std::copy(y.begin(), y.end(), x.begin() + 100);  // 100 samples of silence, then the strike
  std::mt19937 gen(3);
  std::normal_distribution<double> noise(0.0, 1e-4);
  for (double& v : x) v += noise(gen);
  const auto set = estimate::extract_features(x, fs, {});
  ASSERT_GE(set.features.size(), truth.size());
  for (const auto& t : truth) {
    const estimate::Feature* best = nullptr;
    for (const auto& f : set.features)
      if (!best || std::abs(f.frequency - t.frequency) < std::abs(best->frequency - t.frequency))
        best = &f;
    EXPECT_NEAR(best->frequency, t.frequency, 1e-4 * t.frequency) << t.frequency;
    EXPECT_NEAR(best->decay, t.decay, 0.02 * t.decay + 3 * best->decay_sigma) << t.frequency;
    // Amplitudes are at the largest sample, a little after the strike at sample 100.
    const double at = t.amplitude * std::exp(-t.decay * double(set.origin - 100) / fs);
    EXPECT_NEAR(best->amplitude, at, 0.02 * at) << t.frequency;
    EXPECT_GT(best->decay_sigma, 0.0);
  }
  EXPECT_GT(set.explained, 0.9);
}

TEST(EstimateDamping, FitsEachModelToExactPartials) {
  const std::vector<DampingModel> models = {{DampingModel::Kind::Rayleigh, {3.0, 4e-9}},
                                            {DampingModel::Kind::PowerLaw, {2e-3, 0.45}},
                                            {DampingModel::Kind::Caughey, {2.0, 1e-8, 1e-17}},
                                            {DampingModel::Kind::Hybrid, {1.0, 1e-9, 5e-3, 0.4}}};
  for (const DampingModel& m : models) {
    std::vector<estimate::Feature> fs;
    for (double f = 100; f < 12000; f *= 1.4) {
      estimate::Feature x;
      x.frequency = f;
      x.decay = 0.5 * m.coefficient(kTwoPi * f);
      x.decay_sigma = 1e-3 * x.decay;
      fs.push_back(x);
    }
    DampingModel shape = m;
    for (double& a : shape.alpha) a = 0;
    const auto fit = estimate::fit_damping(fs, shape);
    EXPECT_LT(curve_error(fit.model, m, 100, 10000), 0.01)
        << m.to_string() << " -> " << fit.model.to_string();
  }
}

TEST(EstimateDamping, RefusesTooFewPartialsAndBadKinds) {
  std::vector<estimate::Feature> one(1);
  one[0].frequency = 440, one[0].decay = 2, one[0].decay_sigma = 0.01;
  EXPECT_THROW(estimate::fit_damping(one, estimate::damping_kind("power")), InputError);
  EXPECT_THROW(estimate::damping_kind("caughey:9"), InputError);
  EXPECT_THROW(estimate::damping_kind("viscous"), InputError);
  EXPECT_EQ(estimate::damping_kind("caughey:4").alpha.size(), 4u);
}

struct RoundTrip {
  estimate::FeatureSet features;
  estimate::DampingFit curve;
  estimate::MaterialFit fit;
  double gamma = 0;  // the rendered bar's E / rho
};

// Renders the bar in `E` and `damping`, then estimates from the sound with the reference steel
// bar's modes, struck and heard where the rendering was.
RoundTrip round_trip(double E, const DampingModel& damping, double snr_db) {
  const Rendered r = render_bar(E, damping, snr_db);
  RoundTrip t;
  t.gamma = E / r.bar.density;
  t.features = estimate::extract_features(r.x, r.fs, {});
  DampingModel shape = damping;
  for (double& a : shape.alpha) a = 0;
  t.curve = estimate::fit_damping(t.features.features, shape);
  BarSpec reference = r.bar;
  reference.youngs_modulus = 200e9;
  const ModalModel model = analytic_bar(reference);
  const auto modes = estimate::struck_modes(model, model.nearest_point(r.point), r.listener,
                                            reference.youngs_modulus / reference.density);
  estimate::MaterialFitOptions o;
  o.shape = shape;
  t.fit = estimate::fit_material(r.x, r.fs, t.features, modes, t.curve, o);
  return t;
}

TEST(EstimateMaterial, RecoversARenderedBarsMaterialForEachDampingModel) {
  const std::vector<std::pair<double, DampingModel>> cases = {
      {70e9, {DampingModel::Kind::PowerLaw, {3e-4, 0.5}}},
      {120e9, {DampingModel::Kind::Rayleigh, {4.0, 2e-9}}},
      {200e9, {DampingModel::Kind::Caughey, {2.0, 3e-9, 1e-18}}},
      {45e9, {DampingModel::Kind::Hybrid, {1.0, 5e-10, 2e-3, 0.35}}}};
  for (const auto& [E, damping] : cases) {
    const RoundTrip t = round_trip(E, damping, 30.0);
    SCOPED_TRACE(damping.to_string() + " E " + std::to_string(E));
    EXPECT_LT(curve_error(t.curve.model, damping, 100, 10000), 0.03)
        << "through the partials: " << t.curve.model.to_string();
    EXPECT_NEAR(t.fit.gamma, t.gamma, 0.03 * t.gamma);
    EXPECT_LT(curve_error(t.fit.damping, damping, 100, 10000), 0.03)
        << "fitted: " << t.fit.damping.to_string() << " contact " << t.fit.contact_time;
    EXPECT_NEAR(t.fit.contact_time, 3e-4, 1e-4);
  }
}

// The partials of the bundled recordings (recordings/README.md), as a 1 M-point FFT peak search
// finds them (docs/validation.md); the marimba's fundamental decays as a clean exponential at
// 4.70 1/s (scripts/recording_decays.py).
TEST(EstimateRecordings, FindsThePartialsOfEachRecording) {
  struct Case {
    const char* file;
    double end;
    std::vector<double> partials;
  };
  const Case cases[] = {
      {"glockenspiel_C6.wav",
       0.798,
       {1049.77, 2877.53, 5553.96, 7225.91, 9107.10, 11016.02, 12930.20, 13339.20}},
      {"marimba_C4.wav", 0, {261.58, 784.75, 1046.33, 1307.92}},
      {"xylophone_C5.wav", 0, {523.18, 1566.59, 3033.57}},
      {"woodblock_C4.wav", 0, {1636.88}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const auto rec = estimate::read_recording(
        CHLADNI_SOURCE_DIR "/recordings/" + std::string(c.file), {0, c.end});
    estimate::check_recording(rec);
    const auto set = estimate::extract_features(rec.samples, rec.sample_rate, {});
    for (double f : c.partials) {
      const estimate::Feature* near = nullptr;
      for (const auto& g : set.features)
        if (std::abs(g.frequency - f) < 0.005 * f) near = &g;
      ASSERT_NE(near, nullptr) << f << " Hz not found";
      EXPECT_GT(near->decay, 0.0) << f;
      EXPECT_GT(near->decay_sigma, 0.0) << f;
      EXPECT_LT(near->decay_sigma, near->decay) << f;
      if (f == 261.58) {
        EXPECT_NEAR(near->decay, 4.70, 0.03 * 4.70);
      }
    }
  }
}

// A recording file of `frames` samples per channel from `gen(frame, channel)`.
std::string write_recording(const std::string& name, int rate, int channels, std::size_t frames,
                            const std::function<float(std::size_t, int)>& gen) {
  AudioBuffer b;
  b.sample_rate = rate;
  b.channels = channels;
  for (std::size_t i = 0; i < frames; ++i)
    for (int c = 0; c < channels; ++c) b.samples.push_back(gen(i, c));
  const std::string path = test::temp_path(name);
  write_wav(path, b);
  return path;
}

float strike(std::size_t i, double fs, double gain = 0.5) {
  const double t = double(i) / fs;
  return float(gain * std::exp(-6 * t) * std::sin(kTwoPi * 440 * t) +
               0.5 * gain * std::exp(-15 * t) * std::sin(kTwoPi * 1210 * t));
}

void expect_refused(const std::string& path, const std::string& words) {
  try {
    estimate::check_recording(estimate::read_recording(path));
    ADD_FAILURE() << path << " was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(words), std::string::npos) << msg;
  }
}

TEST(EstimateRecordings, BadRecordingsAreRefusedOrHandledAsDocumented) {
  const double fs = 44100;
  expect_refused(write_recording("est_silent.wav", 44100, 1, 44100, [](auto, int) { return 0.f; }),
                 "silent");
  expect_refused(write_recording("est_dc.wav", 44100, 1, 44100, [](auto, int) { return 0.3f; }),
                 "DC");
  expect_refused(write_recording("est_short.wav", 44100, 1, 1000,
                                 [&](std::size_t i, int) { return strike(i, fs); }),
                 "50 ms");
  expect_refused(test::temp_path(""), "not a regular file");
  expect_refused(write_recording("est_rate.wav", 3000, 1, 3000,
                                 [&](std::size_t i, int) { return strike(i, 3000); }),
                 "sample rate 3000 Hz");
  // Channels are mixed to mono: a stereo file with the strike in one channel gives the mono
  // file's partials at half the amplitude.
  const auto mono = estimate::read_recording(write_recording(
      "est_mono.wav", 44100, 1, 44100, [&](std::size_t i, int) { return strike(i, fs); }));
  const auto stereo = estimate::read_recording(
      write_recording("est_stereo.wav", 44100, 2, 44100,
                      [&](std::size_t i, int c) { return c == 0 ? strike(i, fs) : 0.f; }));
  EXPECT_EQ(stereo.channels, 2);
  const auto a = estimate::extract_features(mono.samples, fs, {});
  const auto b = estimate::extract_features(stereo.samples, fs, {});
  ASSERT_EQ(a.features.size(), b.features.size());
  for (std::size_t i = 0; i < a.features.size(); ++i) {
    EXPECT_NEAR(a.features[i].frequency, b.features[i].frequency, 1e-6 * a.features[i].frequency);
    EXPECT_NEAR(b.features[i].amplitude, 0.5 * a.features[i].amplitude,
                1e-4 * a.features[i].amplitude);
  }
  // A clipped strike is counted, and analysis starts after the clipped run.
  const auto clipped = estimate::read_recording(write_recording(
      "est_clipped.wav", 44100, 1, 44100,
      [&](std::size_t i, int) { return std::clamp(strike(i, fs, 3.0), -1.f, 1.f); }));
  EXPECT_GT(clipped.clipped, 0u);
  const auto c = estimate::extract_features(clipped.samples, fs, {});
  ASSERT_FALSE(c.features.empty());
  EXPECT_NEAR(c.features[0].frequency, 440, 0.5);
  EXPECT_NEAR(c.features[0].decay, 6, 0.2);
  // An odd rate is read as it is; partials stay below 0.45 of it.
  const auto odd = estimate::read_recording(write_recording(
      "est_11025.wav", 11025, 1, 11025, [&](std::size_t i, int) { return strike(i, 11025); }));
  const auto o = estimate::extract_features(odd.samples, odd.sample_rate, {});
  ASSERT_GE(o.features.size(), 2u);
  EXPECT_NEAR(o.features[1].frequency, 1210, 0.5);
}

}  // namespace
}  // namespace chladni
