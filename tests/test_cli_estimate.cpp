// chladni estimate end to end: a soundbank struck by `chladni render`, its material and damping
// recovered, saved as a preset and used by precompute; bad input exits with 2 and names it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "browser.hpp"
#include "chladni/core/damping.hpp"
#include "cli_support.hpp"
#include "test_support.hpp"

namespace {

using chladni::test::run_cli;
using chladni::test::temp_path;

constexpr double kTwoPi = 6.283185307179586;

// The bar (steel:constant, power:3e-4,0.5) struck on its top face, heard 1 m above: a bank
// made once.
struct StruckBar {
  std::string bank = temp_path("est_cli_bar.chbank"), wav = temp_path("est_cli_bar.wav");
  StruckBar() {
    auto r = run_cli("precompute " CHLADNI_SOURCE_DIR "/meshes/bar.obj -o " + bank +
                     " --max-modes 14 --no-transfer --material steel:constant --quiet");
    EXPECT_EQ(r.code, 0) << r.output;
    const std::string scene =
        chladni::test::write_temp("est_cli_scene.json",
                                  R"({"sample_rate": 44100, "channels": 1, "duration": 2.5,
            "listener": {"position": [0.05, 0, 1], "forward": [0, 1, 0], "up": [0, 0, 1]},
            "objects": [{"name": "bar", "soundbank": ")" +
                                      bank + R"("}],
            "events": [{"time": 0.02, "type": "impact", "object": "bar", "impulse": 0.02,
                        "direction": [0, 0, -1], "point": [0.05, 0.004, 0.005],
                        "contact_time": 0.0002}]})");
    r = run_cli("render " + scene + " -o " + wav + " --quiet");
    EXPECT_EQ(r.code, 0) << r.output;
  }
};

const StruckBar& struck_bar() {
  static const StruckBar bar;
  return bar;
}

TEST(CliEstimate, RecoversTheBanksMaterialAndSavesItAsAPreset) {
  const StruckBar& bar = struck_bar();
  const std::string json = temp_path("est_cli.json"), resynth = temp_path("est_cli_re.wav"),
                    presets = temp_path("est_cli_materials.json");
  std::filesystem::remove(presets);
  const std::string env = "CHLADNI_MATERIALS=" + presets;
  auto r = run_cli("estimate " + bar.wav + " --bank " + bar.bank +
                       " --hit-point 0.05,0.004,0.005 --listener 0.05,0,1 --json " + json +
                       " --resynth " + resynth + " --save-material my-bar",
                   env);
  ASSERT_EQ(r.code, 0) << r.output;
  const auto j = nlohmann::json::parse(std::ifstream(json));
  EXPECT_NEAR(j["material"]["frequency_scale"].get<double>(), 1.0, 0.005);
  EXPECT_NEAR(j["material"]["E_pa"].get<double>(), 200e9, 0.01 * 200e9);
  EXPECT_NEAR(j["material"]["contact_time_s"].get<double>(), 2e-4, 0.5e-4);
  const auto fitted = chladni::DampingModel::parse(j["material"]["damping"].get<std::string>());
  const chladni::DampingModel truth{chladni::DampingModel::Kind::PowerLaw, {3e-4, 0.5}};
  for (double f = 100; f <= 10000; f *= 1.5)
    EXPECT_NEAR(fitted.coefficient(kTwoPi * f) / truth.coefficient(kTwoPi * f), 1.0, 0.03) << f;
  EXPECT_GE(j["recordings"][0]["features"].size(), 6u);
  EXPECT_TRUE(std::filesystem::file_size(resynth) > 1000);

  // The saved preset is a material precompute takes by name.
  r = run_cli("materials", env);
  EXPECT_NE(r.output.find("my-bar"), std::string::npos) << r.output;
  const std::string bank2 = temp_path("est_cli_mybar.chbank");
  r = run_cli("precompute " CHLADNI_SOURCE_DIR "/meshes/bar.obj -o " + bank2 +
                  " --material my-bar --max-modes 4 --no-transfer --quiet",
              env);
  ASSERT_EQ(r.code, 0) << r.output;
  r = run_cli("info " + bank2 + " --json");
  EXPECT_EQ(nlohmann::json::parse(r.output)["material"]["name"], "my-bar");
}

TEST(CliEstimate, SolvesAMeshForItsModesFirst) {
  const StruckBar& bar = struck_bar();
  const std::string json = temp_path("est_cli_mesh.json");
  const auto r = run_cli("estimate " + bar.wav +
                         " --mesh " CHLADNI_SOURCE_DIR
                         "/meshes/bar.obj --mesh-modes 14 --material steel:constant "
                         "--hit-point 0.05,0.004,0.005 --listener 0.05,0,1 --json " +
                         json);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("solving the modes of"), std::string::npos) << r.output;
  const auto j = nlohmann::json::parse(std::ifstream(json));
  EXPECT_EQ(j["object"]["modes"].get<int>(), 14);
  EXPECT_NEAR(j["material"]["E_pa"].get<double>(), 200e9, 0.01 * 200e9);
}

// The plot's pixels: 8-bit RGB, row major.
// Mean of a pixel's three channels, 0 (black) to 1 (white).
double brightness(const chladni::test::Image& img, unsigned x, unsigned y) {
  const uint8_t* p = img.at(int(x), int(y));
  return (p[0] + p[1] + p[2]) / (3 * 255.0);
}

TEST(CliEstimate, PlotsLabelledSpectrogramsAndTheDampingCurve) {
  const StruckBar& bar = struck_bar();
  const std::string png = temp_path("est_cli_plot.png");
  const auto r = run_cli("estimate " + bar.wav + " --bank " + bar.bank +
                         " --hit-point 0.05,0.004,0.005 --listener 0.05,0,1 --plot " + png);
  ASSERT_EQ(r.code, 0) << r.output;
  const chladni::test::Image img = chladni::test::read_png(png);
  ASSERT_EQ(img.width, 1400);
  ASSERT_EQ(img.height, 1000);
  // The recorded spectrogram (x 90-610, y 70-450, log frequency 50 Hz-22.05 kHz): the bar's
  // second bending mode (about 1,574 Hz) is a bright row where the log axis puts it; at 1 kHz,
  // between partials, the rows stay dark.
  auto row_of = [](double f) {
    return unsigned(70 + 380 * (1 - std::log(f / 50) / std::log(22050.0 / 50)));
  };
  double on = 0, off = 0;
  for (unsigned x = 100; x < 300; ++x) {
    on = std::max(on, brightness(img, x, row_of(1574)));
    off = std::max(off, brightness(img, x, row_of(1000)));
  }
  EXPECT_GT(on, 0.3);
  EXPECT_LT(off, 0.1) << on;
  // Tick labels left of each panel and under it: dark pixels on the white margin.
  auto dark = [&](unsigned x0, unsigned x1, unsigned y0, unsigned y1) {
    std::size_t n = 0;
    for (unsigned y = y0; y < y1; ++y)
      for (unsigned x = x0; x < x1; ++x) n += brightness(img, x, y) < 0.5;
    return n;
  };
  EXPECT_GT(dark(40, 86, 80, 440), 200u);    // frequency ticks
  EXPECT_GT(dark(90, 610, 452, 500), 100u);  // time ticks and label
  EXPECT_GT(dark(40, 86, 570, 920), 200u);   // damping ratio ticks
  // The damping panel has its points and curves (coloured pixels inside the frame).
  std::size_t coloured = 0;
  for (unsigned y = 565; y < 925; ++y)
    for (unsigned x = 95; x < 1305; ++x) {
      const uint8_t* p = img.at(int(x), int(y));
      coloured += std::abs(int(p[0]) - int(p[2])) > 60;
    }
  EXPECT_GT(coloured, 500u);
}

TEST(CliEstimate, BadInputExitsWith2AndNamesIt) {
  const StruckBar& bar = struck_bar();
  const std::string dir = temp_path("");
  struct Case {
    std::string args, words;
  };
  const Case cases[] = {
      {"", "name a recording"},
      {"/nonexistent/strike.wav", "/nonexistent/strike.wav: no such file"},
      {dir, "not a regular file"},
      {bar.wav + " --explained nan", "--explained"},
      {bar.wav + " --damping caughey:9", "caughey:K"},
      {bar.wav + " --bank " + bar.bank, "--hit-vertex or --hit-point"},
      {bar.wav + " --hit-vertex 3", "need --bank or --mesh"},
      {bar.wav + " --bank " + bar.bank + " --hit-vertex 99999999", "out of range"},
      {bar.wav + " --bank " + bar.bank + " --hit-vertex 1 --save-material steel", "shipped preset"},
      {bar.wav + " --start 5", "nothing between"},
      {bar.wav + " --json " + dir, "--json"},
      {bar.wav + " --plot " + dir, "--plot"},
      {bar.wav + " " + bar.wav + " --resynth " + temp_path("est_two.wav"), "one recording"},
  };
  for (const Case& c : cases) {
    const auto r = run_cli("estimate " + c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.words), std::string::npos) << c.args << "\n" << r.output;
  }
}

}  // namespace
