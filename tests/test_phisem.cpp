// PhISEM: the model's statistics against its parameters, our shakers against STK's Shakers class
// (Cook's own implementation, Debian's libstk), determinism, and the GPU excitation and filterbank
// against the CPU sample by sample.
#include <Shakers.h>
#include <fftw3.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <numbers>
#include <vector>

#include "chladni/core/analytic_bar.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/gpu/buffer.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::runtime;
using chladni::test::max_abs;
using chladni::test::max_diff;

namespace {

constexpr double kFs = 44100;  // STK's rate, so that both use the presets' own constants

// Energy envelope decay time (s to fall 60 dB): least-squares slope of 10 log10(frame energy)
// from the peak frame down to 30 dB below it, 5 ms frames.
double decay_time(const std::vector<float>& x, double fs) {
  const std::size_t hop = static_cast<std::size_t>(0.005 * fs);
  std::vector<double> db;
  for (std::size_t i = 0; i + hop <= x.size(); i += hop) {
    double e = 0;
    for (std::size_t k = i; k < i + hop; ++k) e += double(x[k]) * x[k];
    db.push_back(10 * std::log10(e + 1e-300));
  }
  std::size_t peak = 0;
  for (std::size_t i = 1; i < db.size(); ++i)
    if (db[i] > db[peak]) peak = i;
  std::size_t end = peak;
  while (end + 1 < db.size() && db[end + 1] > db[peak] - 30) ++end;
  double st = 0, sy = 0, stt = 0, sty = 0, n = 0;
  for (std::size_t i = peak; i <= end; ++i) {
    const double t = double(i) * hop / fs;
    st += t, sy += db[i], stt += t * t, sty += t * db[i], n += 1;
  }
  const double slope = (n * sty - st * sy) / (n * stt - st * st);  // dB/s, negative
  return -60.0 / slope;
}

// Power-weighted mean frequency (Hz) of the whole signal.
double spectral_centroid(const std::vector<float>& x, double fs) {
  const int n = static_cast<int>(x.size());
  std::vector<float> in(x);
  std::vector<fftwf_complex> out(n / 2 + 1);
  fftwf_plan plan = fftwf_plan_dft_r2c_1d(n, in.data(), out.data(), FFTW_ESTIMATE);
  fftwf_execute(plan);
  fftwf_destroy_plan(plan);
  double num = 0, den = 0;
  for (int k = 0; k <= n / 2; ++k) {
    const double p = double(out[k][0]) * out[k][0] + double(out[k][1]) * out[k][1];
    num += p * k * fs / n;
    den += p;
  }
  return num / den;
}

// One second of STK's shaker `type` after noteOn(amplitude 1), seeded through rand().
std::vector<float> stk_shaker(int type, unsigned seed) {
  stk::Stk::setSampleRate(kFs);
  std::srand(seed);
  stk::Shakers s(type);
  // noteOn picks the instrument from a "frequency" read as a MIDI note number mod 32.
  s.noteOn(220.0 * std::pow(2.0, (type - 57) / 12.0), 1.0);
  std::vector<float> out(static_cast<std::size_t>(kFs));
  for (float& y : out) y = static_cast<float>(s.tick());
  return out;
}

// One second of ours: one voice, one shake of STK's noteOn energy (0.1).
std::vector<float> our_shaker(const std::string& name, uint64_t seed) {
  CpuFilterbank fb({.capacity = 64, .channels = 1, .threads = 1});
  ShakerBank bank(fb, {.sample_rate = kFs, .max_voices = 1, .seed = seed});
  bank.add_voice(instrument_voice(phisem_preset(name), kFs));
  const TimedShake shake{0.0, 0, 0.1f};
  return render_shaker(bank, 1, kFs, std::span(&shake, 1), 1.0, 256).samples;
}

struct Measured {
  double decay = 0, centroid = 0;
};

Measured average(auto make, int seeds) {
  Measured m;
  for (int s = 1; s <= seeds; ++s) {
    const std::vector<float> x = make(s);
    m.decay += decay_time(x, kFs) / seeds;
    m.centroid += spectral_centroid(x, kFs) / seeds;
  }
  return m;
}

}  // namespace

TEST(Phisem, MatchesStkShakersInDecayTimeAndSpectralCentroid) {
  const struct {
    const char* name;
    int stk_type;
  } cases[] = {{"maraca", 0}, {"cabasa", 1}, {"tambourine", 3}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const Measured stk = average([&](int s) { return stk_shaker(c.stk_type, unsigned(s)); }, 20);
    const Measured ours = average([&](int s) { return our_shaker(c.name, uint64_t(s)); }, 20);
    std::printf("%-10s decay ours %.4f s STK %.4f s; centroid ours %.0f Hz STK %.0f Hz\n", c.name,
                ours.decay, stk.decay, ours.centroid, stk.centroid);
    EXPECT_NEAR(ours.decay / stk.decay, 1.0, 0.15)
        << "decay time: ours " << ours.decay << " s, STK " << stk.decay << " s";
    EXPECT_NEAR(ours.centroid / stk.centroid, 1.0, 0.15)
        << "centroid: ours " << ours.centroid << " Hz, STK " << stk.centroid << " Hz";
  }
}

TEST(Phisem, CollisionRateFollowsTheParticleCount) {
  // Collisions happen with probability N / 1024 per (reference) sample while the energy is above
  // the threshold: after one full shake, for ln(0.001) / ln(system decay) samples.
  const PhisemPreset& maraca = phisem_preset("maraca");
  for (double n : {4.0, 32.0, 256.0}) {
    const PhisemParams p = phisem_params(maraca, kFs, n);
    const double active = std::ceil(std::log(kPhisemMinEnergy) / std::log(double(p.system_decay)));
    const double expected = active * n / 1024.0;
    double total = 0;
    const int runs = 200;
    std::vector<float> out(20000);
    for (int r = 0; r < runs; ++r) {
      PhisemState st;
      st.key = phisem_key(99, r);
      const Shake s{0, 0, 1.0f};
      phisem_generate(p, st, std::span(&s, 1), 20000, out.data());
      total += st.collisions;
      // The event list of one shake makes the same decisions as the generator.
      ASSERT_EQ(phisem_collisions(p, st.key, 1.0f).size(), st.collisions);
    }
    // Poisson: the mean of 200 runs is within 4 standard errors.
    const double mean = total / runs, se = std::sqrt(expected / runs);
    EXPECT_NEAR(mean, expected, 4 * se + 0.01 * expected) << "N = " << n;
  }
  // At another sample rate the rate per second is the same.
  const PhisemParams p48 = phisem_params(maraca, 48000), p44 = phisem_params(maraca, kFs);
  EXPECT_NEAR(p48.collision_probability * 48000, p44.collision_probability * kFs, 1e-3);
}

TEST(Phisem, EnergyAndSoundLevelDecayAtTheirRates) {
  PhisemParams p = phisem_params(phisem_preset("maraca"), kFs);
  // System energy: energy_n = amount * system_decay^n exactly as a float recurrence.
  {
    PhisemState st;
    p.collision_probability = 0;
    const Shake s{0, 0, 0.5f};
    std::vector<float> out(1000);
    phisem_generate(p, st, std::span(&s, 1), 1000, out.data());
    EXPECT_NEAR(st.energy, 0.5 * std::pow(double(p.system_decay), 1000), 1e-5);
    for (float x : out) EXPECT_EQ(x, 0.0f);  // no collision, no sound
  }
  // Sound level: mean x^2 over many streams follows level^2 sound_decay^(2n) / 3 (uniform noise).
  p.eq[0] = 1, p.eq[1] = 0, p.eq[2] = 0, p.gain = 1;
  const int runs = 4000, n = 60;
  std::vector<double> power(n, 0.0);
  std::vector<float> out(n);
  for (int r = 0; r < runs; ++r) {
    PhisemState st;
    st.key = phisem_key(7, r);
    st.level = 1.0f;
    phisem_generate(p, st, {}, n, out.data());
    for (int k = 0; k < n; ++k) power[k] += double(out[k]) * out[k] / runs;
  }
  for (int k : {0, 20, 40}) {
    const double expect = std::pow(double(p.sound_decay), 2.0 * k) / 3.0;
    EXPECT_NEAR(power[k] / expect, 1.0, 0.08) << "sample " << k;
  }
}

TEST(Phisem, FixedSeedGivesTheSameSoundAndAnotherSeedAnother) {
  const auto a = our_shaker("tambourine", 5), b = our_shaker("tambourine", 5),
             c = our_shaker("tambourine", 6);
  ASSERT_GT(max_abs(a), 0.0);
  EXPECT_EQ(max_diff(a, b), 0.0);
  EXPECT_GT(max_diff(a, c), 0.01 * max_abs(a));
}

TEST(Phisem, PresetsAndParametersAreValidated) {
  for (const std::string name : {"maraca", "cabasa", "sekere", "tambourine", "sleighbells",
                                 "bamboo", "water", "rain", "coins", "paper"}) {
    const PhisemPreset& p = phisem_preset(name);
    EXPECT_FALSE(p.source.empty()) << name;
    const ShakerVoice v = instrument_voice(p, 48000);
    EXPECT_EQ(v.resonances.size(), p.resonances.size());
  }
  try {
    phisem_preset("kazoo");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown instrument 'kazoo' (known: maraca"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(phisem_params(phisem_preset("maraca"), 48000, std::nan("")), InputError);
  EXPECT_THROW(phisem_params(phisem_preset("maraca"), 48000, -3), InputError);
  // A resonance above Nyquist at this rate is refused, not aliased.
  EXPECT_THROW(instrument_voice(phisem_preset("coins"), 16000), InputError);
  CpuFilterbank fb({.capacity = 4, .channels = 1, .threads = 1});
  ShakerBank bank(fb, {.sample_rate = 48000, .max_voices = 2});
  ShakerVoice v = instrument_voice(phisem_preset("maraca"), 48000);
  v.resonances[0].decay = std::nan("");
  EXPECT_THROW(bank.add_voice(v), InputError);
  EXPECT_THROW(bank.add_voice(instrument_voice(phisem_preset("sleighbells"), 48000)),
               InputError);              // 5 resonances, 4 slots
  EXPECT_FALSE(bank.shake(0, 1.0f, 0));  // no such voice
  EXPECT_EQ(bank.add_voice(instrument_voice(phisem_preset("maraca"), 48000)), 0);
  EXPECT_FALSE(bank.shake(0, std::nanf(""), 0));
  EXPECT_TRUE(bank.shake(0, 0.5f, 10));
}

TEST(Phisem, RemovedVoicesGiveTheirSlotsAndIndexToLaterOnes) {
  const ShakerVoice bells = instrument_voice(phisem_preset("sleighbells"), 48000);
  const auto n = static_cast<uint32_t>(bells.resonances.size());
  CpuFilterbank fb({.capacity = 2 * n, .channels = 1, .threads = 1});
  ShakerBank bank(fb, {.sample_rate = 48000, .max_voices = 3, .reserve_all = true});
  EXPECT_EQ(bank.add_voice(bells), 0);
  EXPECT_EQ(bank.add_voice(bells), 1);
  EXPECT_THROW(bank.add_voice(bells), InputError);  // every slot taken
  std::vector<float> out(256);
  EXPECT_TRUE(bank.shake(0, 1.0f, 0));
  bank.render(256, out.data());
  EXPECT_GT(test::max_abs(out), 0.0);
  // Removed, a voice is silent at once and refuses shakes; its slots and index go to the next.
  bank.remove_voice(0);
  EXPECT_FALSE(bank.live(0));
  EXPECT_FALSE(bank.shake(0, 1.0f, 0));
  bank.render(256, out.data());
  EXPECT_EQ(test::max_abs(out), 0.0);
  auto again = ShakerBank::prepare_voice(bells);
  EXPECT_FALSE(bank.add_voice(*again, 1));  // taken
  EXPECT_TRUE(bank.add_voice(*again, 0));
  // Two neighbouring runs freed merge: a voice of both their sizes fits.
  bank.remove_voice(0);
  bank.remove_voice(1);
  ShakerVoice twice = bells;
  twice.resonances.insert(twice.resonances.end(), bells.resonances.begin(), bells.resonances.end());
  auto wide = ShakerBank::prepare_voice(twice);
  EXPECT_TRUE(bank.add_voice(*wide, 1));
  EXPECT_TRUE(bank.shake(1, 1.0f, 0));
  bank.render(256, out.data());
  EXPECT_GT(test::max_abs(out), 0.0);
}

namespace {

// A few voices of several kinds (fixed, retuned, soundbank modes) over two seconds.
AudioBuffer mixed_run(Filterbank& fb, ExcitationBackend excitation, const ObjectModes& bar,
                      std::vector<std::vector<float>>* inputs = nullptr) {
  const double fs = 48000;
  ShakerBank bank(fb, {.sample_rate = fs, .max_voices = 8, .seed = 42, .excitation = excitation});
  for (const char* name : {"maraca", "tambourine", "sleighbells", "water", "cabasa"})
    bank.add_voice(instrument_voice(phisem_preset(name), fs));
  bank.add_voice(object_voice(phisem_preset("gravel"), bar, fs, 1e-3, 4, 42));
  const auto shakes = regular_shakes(bank.voice_count(), 5.0, 1.5, 0.4f);
  AudioBuffer audio;
  audio.sample_rate = 48000;
  audio.channels = 1;
  std::size_t next = 0;
  std::vector<float> buf(256);
  for (uint64_t t = 0; t < 96000; t += 256) {
    for (; next < shakes.size() && shakes[next].time * fs < double(t + 256); ++next)
      bank.shake(shakes[next].voice, shakes[next].amount,
                 static_cast<uint32_t>(std::max(0.0, std::round(shakes[next].time * fs) - t)));
    bank.render(256, buf.data());
    audio.samples.insert(audio.samples.end(), buf.begin(), buf.end());
    if (inputs) {  // the excitation of this block, as made by the chosen backend
      const float* src =
          excitation == ExcitationBackend::Gpu
              ? static_cast<const float*>(dynamic_cast<GpuFilterbank&>(fb).input_buffer().data())
              : bank.last_input();
      inputs->emplace_back(src, src + std::size_t(bank.voice_count()) * 256);
    }
  }
  return audio;
}

}  // namespace

TEST(Phisem, GpuExcitationAndFilterbankAgreeWithTheCpu) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  ModalModel model = analytic_bar({});
  model.name = "bar";
  const ObjectModes bar = object_modes(model);
  CpuFilterbank cpu({.capacity = 4096, .channels = 1, .threads = 2});
  GpuFilterbank gpu(ctx, {.capacity = 4096, .channels = 1, .max_streams = 8});
  std::vector<std::vector<float>> cin, gin;
  const AudioBuffer a = mixed_run(cpu, ExcitationBackend::Cpu, bar, &cin);
  const AudioBuffer b = mixed_run(gpu, ExcitationBackend::Gpu, bar, &gin);
  // The excitation is the same bit for bit: same random numbers, same float operations.
  ASSERT_EQ(cin.size(), gin.size());
  for (std::size_t k = 0; k < cin.size(); ++k) ASSERT_EQ(cin[k], gin[k]) << "block " << k;
  const double peak = max_abs(a.samples);
  ASSERT_GT(peak, 1e-3);
  EXPECT_LT(max_diff(a.samples, b.samples), 1e-4 * peak);
  // The GPU run is deterministic too.
  GpuFilterbank gpu2(ctx, {.capacity = 4096, .channels = 1, .max_streams = 8});
  const AudioBuffer c = mixed_run(gpu2, ExcitationBackend::Gpu, bar);
  EXPECT_EQ(max_diff(b.samples, c.samples), 0.0);
  EXPECT_EQ(ctx->validation_errors(), 0u);
}

TEST(Phisem, ObjectVoiceDrivesTheModesThroughTheContactShapes) {
  ModalModel model = analytic_bar({});
  model.name = "bar";
  const ObjectModes bar = object_modes(model);
  const ShakerVoice v = object_voice(phisem_preset("gravel"), bar, 48000, 2e-3, 3, 9);
  ASSERT_EQ(v.resonances.size(), model.mode_count());
  ASSERT_EQ(v.contacts.size(), 3u);
  for (std::size_t i = 0; i < model.mode_count(); ++i) {
    EXPECT_DOUBLE_EQ(v.resonances[i].omega_d, model.damped_omega(i));
    EXPECT_DOUBLE_EQ(v.resonances[i].decay, model.decay[i]);
  }
  // Each contact's kicks are (v_i(x) . n) J / omega_d at one surface point: find it.
  for (const auto& c : v.contacts) {
    bool found = false;
    for (std::size_t pnt = 0; pnt < model.points.size() && !found; ++pnt) {
      const Vec3 dir = model.normals.empty() ? Vec3{0, 0, -1} : scale(model.normals[pnt], -1.0);
      bool all = true;
      for (std::size_t i = 0; i < model.mode_count() && all; ++i) {
        const double expect = dot(model.shape(i, pnt), dir) * 2e-3 / model.damped_omega(i);
        all = std::abs(c[i].real() - expect) <= 1e-6 * std::abs(expect) + 1e-12;
      }
      found = all;
    }
    EXPECT_TRUE(found);
  }
  ModalModel bare = model;
  bare.points.clear();
  bare.shapes.clear();
  bare.normals.clear();
  EXPECT_THROW(object_voice(phisem_preset("gravel"), object_modes(bare), 48000, 1e-3, 1, 1),
               InputError);
}

TEST(Phisem, SceneShakeEventsRenderOnBothBackendsAndNameBadInput) {
  const nlohmann::json j = nlohmann::json::parse(R"({
    "sample_rate": 48000, "channels": 2, "duration": 1.5,
    "objects": [
      {"name": "bar", "position": [0.3, 1, 0], "bar": {"length": 0.3}},
      {"name": "cup", "position": [-0.5, 1, 0],
       "modes": [{"frequency": 900, "decay": 8, "amplitude": 0.2}]}
    ],
    "events": [
      {"time": 0.0, "type": "shake", "object": "bar", "instrument": "gravel", "energy": 0.8},
      {"time": 0.3, "type": "shake", "object": "bar", "instrument": "gravel", "energy": 0.5},
      {"time": 0.2, "type": "shake", "object": "cup", "instrument": "coins"},
      {"time": 0.5, "type": "shake", "object": "cup", "instrument": "maraca",
       "resonate": "instrument"},
      {"time": 0.7, "type": "impact", "object": "cup", "impulse": 0.01}
    ]})");
  const Scene scene = parse_scene(j, ".");
  ASSERT_EQ(scene.shakes.size(), 4u);
  ModalModel bar_model = analytic_bar(scene.objects[0].bar);
  bar_model.name = "bar";
  std::vector<ObjectModes> objects = {object_modes(bar_model),
                                      object_modes(scene.objects[1].modes)};
  const SceneShakers shakers = scene_shakers(scene, objects);
  ASSERT_EQ(shakers.first_event.size(), 3u);      // the two gravel shakes share a voice
  EXPECT_EQ(shakers.voice[0], shakers.voice[2]);  // sorted by time: gravel, coins, gravel
  EXPECT_EQ(shakers.slots, bar_model.mode_count() + 1 + 1);
  const uint32_t cap = 2048 + shakers.slots;
  RenderOptions ro;
  ro.synth.max_modes = 2048;
  CpuFilterbank cpu({.capacity = cap, .channels = 2, .threads = 2});
  const AudioBuffer a = render_scene(scene, objects, cpu, ro);
  const double peak = max_abs(a.samples);
  ASSERT_GT(peak, 0.0);
  // The shakes sound before the impact at 0.7 s.
  std::vector<float> before(a.samples.begin(), a.samples.begin() + 2 * 33600);
  EXPECT_GT(max_abs(before), 0.05 * peak);
  if (auto ctx = test::gpu_context()) {
    GpuFilterbank gpu(ctx, {.capacity = cap, .channels = 2, .max_streams = 3});
    const AudioBuffer b = render_scene(scene, objects, gpu, ro);
    EXPECT_LT(max_diff(a.samples, b.samples), 1e-4 * peak);
  }
  // Bad input names the event.
  auto error_of = [](const std::string& event) {
    nlohmann::json s = nlohmann::json::parse(
        R"({"objects": [{"name": "cup", "modes": [{"frequency": 900, "decay": 8, "amplitude": 1}]}]})");
    s["events"] = nlohmann::json::array({nlohmann::json::parse(event)});
    try {
      const Scene sc = parse_scene(s, ".");
      scene_shakers(sc, {object_modes(sc.objects[0].modes)});
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error_of(R"({"time": 0, "type": "shake", "object": "cup", "instrument": "maraca",
                         "energy": 2})"),
            "$.events[0].energy: must lie in (0, 1]");
  EXPECT_EQ(error_of(R"({"time": 0, "type": "shake", "object": "cup", "instrument": "maraca",
                         "resonate": "bowl"})"),
            "$.events[0].resonate: must be 'object' or 'instrument', got 'bowl'");
  EXPECT_NE(error_of(R"({"time": 0, "type": "shake", "object": "cup", "instrument": "kazoo"})")
                .find("$.events[0]: unknown instrument 'kazoo'"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"time": 0, "type": "shake", "object": "cup"})")
                .find("missing required field 'instrument'"),
            std::string::npos);
}
