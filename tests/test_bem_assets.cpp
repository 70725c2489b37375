// Boundary elements on a bundled asset, end to end: the bowl's lowest modes by BEM transfer, and
// a rendered strike carries them at the level that transfer predicts.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/soundbank.hpp"
#include "test_support.hpp"

namespace {

int run(const std::string& args, std::string* output) {
  const std::string cmd = std::string(CHLADNI_EXE) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof(buf), p)) output->append(buf, n);
  const int status = pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// |sum_n x[n] e^(-i w n / fs)| over the first `frames` samples.
double dft_magnitude(const chladni::AudioBuffer& a, double omega, std::size_t frames) {
  std::complex<double> s = 0;
  for (std::size_t n = 0; n < frames; ++n)
    s += double(a.samples[n * a.channels]) *
         std::exp(std::complex<double>(0, -omega * n / a.sample_rate));
  return std::abs(s);
}

}  // namespace

TEST(BemAssets, BowlLowestModesByBemAndAudibleAtTheirPredictedLevel) {
  using namespace chladni;
  const std::string bank = test::temp_path("chladni_bem_bowl.chbank");
  std::string out;
  ASSERT_EQ(run("precompute " CHLADNI_SOURCE_DIR
                "/meshes/bowl.obj --material brass --max-modes 4 --transfer-method bem -q -o " +
                    bank,
                &out),
            0)
      << out;
  const Soundbank b = read_soundbank(bank);
  ASSERT_EQ(b.mode_count(), 4u);
  ASSERT_TRUE(b.transfer.has_value());
  for (std::size_t i = 0; i < 4; ++i) {
    const ModeTransfer& m = b.transfer->modes[i];
    EXPECT_EQ(m.method, TransferMethod::Bem) << i;
    EXPECT_EQ(m.sources, b.triangles.size()) << i;
    EXPECT_LT(m.fit_residual, 1e-5) << i;
    EXPECT_LT(m.expansion_error, 0.01) << i;
    EXPECT_TRUE(b.transfer->usable(i)) << i;
  }
  // Strike the rim (no contact time) with the listener 0.6 m away; the 441 Hz pair and the
  // 1142 Hz pair each ring as sum_i |p_i(listener)| (v_i . n) J / w_i e^(-d t) sin(w t).
  const Vec3 object{0, 0.6, 0}, point{0.0797, 0, 0.089}, dir{-1, 0, 0};
  const std::string scene = test::write_temp(
      "chladni_bem_bowl_scene.json",
      "{\"sample_rate\": 48000, \"channels\": 1, \"duration\": 1.0,"
      " \"listener\": {\"position\": [0, 0, 0], \"forward\": [0, 1, 0], \"up\": [0, 0, 1]},"
      " \"objects\": [{\"name\": \"bowl\", \"position\": [0, 0.6, 0], \"soundbank\": \"" +
          bank +
          "\"}], \"events\": [{\"time\": 0.0, \"type\": \"impact\", \"object\": \"bowl\","
          " \"impulse\": 0.01, \"direction\": [-1, 0, 0], \"point\": [0.0797, 0, 0.089]}]}");
  const std::string wav = test::temp_path("chladni_bem_bowl.wav");
  ASSERT_EQ(run("render " + scene + " -o " + wav, &out), 0) << out;
  const AudioBuffer a = read_audio(wav);
  const ModalModel model = to_modal_model(b, "bowl");
  const std::size_t v = model.nearest_point(point);
  const Vec3 listener = sub(Vec3{0, 0, 0}, object);
  const double T = 0.5;
  double measured[2];
  for (std::size_t pair = 0; pair < 2; ++pair) {
    // The pair's two modes differ by a few hundredths of a hertz: synthesize what the transfer
    // predicts and take the same DFT of both.
    AudioBuffer expected{a.sample_rate, 1, std::vector<float>(std::size_t(T * a.sample_rate))};
    double w0 = 0;
    for (std::size_t i = 2 * pair; i < 2 * pair + 2; ++i) {
      const double w = b.damped_omega(i);
      const double amp =
          std::abs(b.transfer->pressure(i, listener)) * dot(model.shape(i, v), dir) * 0.01 / w;
      for (std::size_t n = 0; n < expected.samples.size(); ++n) {
        const double t = double(n) / a.sample_rate;
        expected.samples[n] += float(amp * std::exp(-b.decay[i] * t) * std::sin(w * t));
      }
      w0 = w;
    }
    const double predicted = dft_magnitude(expected, w0, expected.samples.size());
    measured[pair] = dft_magnitude(a, w0, expected.samples.size());
    EXPECT_NEAR(20 * std::log10(measured[pair] / predicted), 0.0, 1.0) << "pair " << pair;
  }
  // The fundamental is not silenced: within 30 dB of the next pair.
  EXPECT_GT(20 * std::log10(measured[0] / measured[1]), -30.0);
}
