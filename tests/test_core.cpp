// Damping models, mode selection, modal-model validation and audio file round trips.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/damping.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/modal_model.hpp"

using namespace chladni;

TEST(Damping, ModelsFollowTheirFormulas) {
  const double w = 2000.0, x = w * w;
  EXPECT_DOUBLE_EQ(DampingModel::parse("rayleigh:3,2e-7").coefficient(w), 3 + 2e-7 * x);
  EXPECT_DOUBLE_EQ(DampingModel::parse("caughey:1,2e-7,3e-15").coefficient(w),
                   1 + 2e-7 * x + 3e-15 * x * x);
  EXPECT_NEAR(DampingModel::parse("power:0.5,0.3").coefficient(w), 0.5 * std::pow(x, 0.3), 1e-12);
  EXPECT_NEAR(DampingModel::parse("hybrid:1,1e-8,0.2,0.25").coefficient(w),
              1 + 1e-8 * x + 0.2 * std::pow(x, 0.25), 1e-12);
  EXPECT_EQ(DampingModel::parse("rayleigh:1,2").to_string(), "rayleigh:1,2");
}

TEST(Damping, BadSpecificationsAreRejectedWithTheReason) {
  auto msg = [](const char* s) {
    try {
      DampingModel::parse(s);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(none)");
  };
  EXPECT_NE(msg("rayleigh:1").find("got 1 parameters"), std::string::npos);
  EXPECT_NE(msg("rayleigh:1,x").find("'x' is not a number"), std::string::npos);
  EXPECT_NE(msg("rayleigh:1,nan").find("not finite"), std::string::npos);
  EXPECT_NE(msg("rayleigh").find("expected NAME:"), std::string::npos);
  EXPECT_THROW(DampingModel::parse("rayleigh:-5,0").coefficient(100.0), InputError);  // c < 0
}

TEST(ModalModel, DampingDropsAndCountsOverdampedAndOutOfBandModes) {
  ModalModel m;
  m.name = "t";
  for (double hz : {10.0, 100.0, 1000.0, 15000.0, 30000.0}) {
    m.omega.push_back(2 * std::numbers::pi * hz);
    m.radiation.push_back(1);
  }
  // Rayleigh with a large stiffness term overdamps the top mode (d = 1e-5 w^2 > w there).
  const ModeSelection sel =
      apply_damping(m, DampingModel::parse("rayleigh:0,2e-5"), 20, 20000, 48000);
  EXPECT_EQ(sel.below_band, 1u);  // 10 Hz
  EXPECT_EQ(sel.overdamped, 1u);  // 30 kHz: d = 1e-5 w^2 = 355306 > w = 188496
  EXPECT_EQ(sel.above_band, 0u);
  ASSERT_EQ(sel.kept, (std::vector<std::size_t>{1, 2, 3}));
  EXPECT_NEAR(m.decay[2], 0.5 * 2e-5 * m.omega[2] * m.omega[2], 1e-9);
  keep_modes(m, sel.kept);
  EXPECT_EQ(m.mode_count(), 3u);
  EXPECT_NEAR(m.damped_omega(0), std::sqrt(m.omega[0] * m.omega[0] - m.decay[0] * m.decay[0]),
              1e-9);
}

TEST(ModalModel, ValidationNamesTheBadMode) {
  ModalModel m;
  m.name = "cup";
  m.omega = {100, NAN};
  m.decay = {1, 1};
  m.radiation = {1, 1};
  try {
    m.validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("modal model 'cup': mode 1"), std::string::npos);
  }
}

TEST(AudioFile, WavRoundTripsFloatAndPcm) {
  AudioBuffer a;
  a.sample_rate = 44100;
  a.channels = 2;
  for (int i = 0; i < 1000; ++i) {
    a.samples.push_back(0.5f * std::sin(0.01f * i));
    a.samples.push_back(-0.25f * std::cos(0.02f * i));
  }
  const auto dir = std::filesystem::temp_directory_path();
  const std::string f32 = (dir / "chladni_rt_f32.wav").string(),
                    p24 = (dir / "chladni_rt_p24.wav").string();
  write_wav(f32, a, SampleFormat::Float32);
  write_wav(p24, a, SampleFormat::Pcm24);
  const AudioBuffer b = read_audio(f32), c = read_audio(p24);
  EXPECT_EQ(b.sample_rate, 44100);
  EXPECT_EQ(b.channels, 2);
  ASSERT_EQ(b.samples.size(), a.samples.size());
  ASSERT_EQ(c.samples.size(), a.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(b.samples[i], a.samples[i]);
    EXPECT_NEAR(c.samples[i], a.samples[i], 2.0 / (1 << 23));
  }
  EXPECT_THROW(write_wav("/nonexistent-dir/x.wav", a), InputError);
  EXPECT_THROW(read_audio("/nonexistent-dir/x.wav"), InputError);
}
