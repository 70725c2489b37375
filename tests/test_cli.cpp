// The chladni command end to end: exit codes, messages, the WAV it writes, bench's JSON.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chladni/core/audio_file.hpp"
#include "test_support.hpp"

namespace {

struct Result {
  int code;
  std::string output;
};

// Runs chladni with `args`; `env` is prepended as VAR=value assignments.
Result run(const std::string& args, const std::string& env = "") {
  const std::string cmd = env + " " + std::string(CHLADNI_EXE) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof(buf), p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace

TEST(Cli, RendersTheExampleSceneToAWav) {
  const std::string out = chladni::test::temp_path("chladni_cli_example.wav");
  const Result r =
      run("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " + out + " --normalize -1");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("576.5"), std::string::npos) << r.output;  // the bar's first mode
  const chladni::AudioBuffer a = chladni::read_audio(out);
  EXPECT_EQ(a.channels, 2);
  EXPECT_EQ(a.sample_rate, 48000);
  EXPECT_GT(a.frames(), 48000u * 3);
  float peak = 0;
  for (float x : a.samples) peak = std::max(peak, std::abs(x));
  EXPECT_NEAR(peak, std::pow(10.0, -1.0 / 20), 1e-3);
}

TEST(Cli, MalformedSceneExitsWith2AndNamesTheJsonPath) {
  const std::string scene = chladni::test::write_temp("chladni_cli_bad.json", R"({
    "objects": [{"name": "a", "modes": [{"frequency": 440, "decay": 1, "amplitude": 1}]}],
    "events": [{"time": 0.1, "type": "impact", "object": "b", "impulse": 1}]})");
  const Result r = run("render " + scene + " -o " + chladni::test::temp_path("x.wav"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("$.events[0].object: unknown object 'b'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(scene), std::string::npos) << r.output;
}

TEST(Cli, BadArgumentsExitWith2) {
  EXPECT_EQ(run("render").code, 2);
  EXPECT_EQ(run("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " +
                chladni::test::temp_path("x.wav") + " --backend tpu")
                .code,
            2);
  EXPECT_EQ(run("render /nonexistent.json -o " + chladni::test::temp_path("x.wav")).code, 2);
  EXPECT_EQ(run("bench --modes 10,abc").code, 2);
  EXPECT_EQ(run("no-such-command").code, 2);
}

TEST(Cli, MissingVulkanDeviceFallsBackToCpuWithOneWarning) {
  // A selector that matches no device is how a machine without one looks to the backend.
  const Result r =
      run("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " +
              chladni::test::temp_path("chladni_cli_fallback.wav") + " --backend gpu --quiet",
          "CHLADNI_VULKAN_DEVICE=no-such-gpu");
  EXPECT_EQ(r.code, 0) << r.output;
  std::size_t count = 0;
  for (std::size_t pos = 0; (pos = r.output.find("warning:", pos)) != std::string::npos; ++pos) {
    ++count;
  }
  EXPECT_EQ(count, 1u) << r.output;
  EXPECT_NE(r.output.find("using the CPU filterbank"), std::string::npos) << r.output;
}

TEST(Cli, BenchJsonHasEveryFieldForEveryBackend) {
  const std::string json_path = chladni::test::temp_path("chladni_bench.json");
  const Result r =
      run("bench --modes 1000,4000 --backend cpu,gpu --seconds 0.05 --json " + json_path);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream f(json_path);
  const nlohmann::json j = nlohmann::json::parse(f);
  ASSERT_EQ(j.size(), 4u);
  for (const auto& rec : j) {
    for (const char* key : {"backend", "device", "modes", "threads", "mode_samples_per_s",
                            "realtime_modes", "block_ms_p50", "block_ms_p99"}) {
      EXPECT_TRUE(rec.contains(key)) << key;
    }
    EXPECT_GT(rec["mode_samples_per_s"].get<double>(), 0.0);
    EXPECT_LE(rec["block_ms_p50"].get<double>(), rec["block_ms_p99"].get<double>());
  }
}

TEST(CliPrecompute, BarToBankToInfoToRender) {
  const std::string bank = chladni::test::temp_path("chladni_cli_bar.chbank"),
                    summary = chladni::test::temp_path("chladni_cli_bar.json");
  Result r = run("precompute " CHLADNI_SOURCE_DIR "/meshes/bar.obj -o " + bank +
                 " --max-modes 6 --max-tet-volume 1e-6 --json " + summary);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("6 rigid modes removed"), std::string::npos) << r.output;
  nlohmann::json j = nlohmann::json::parse(std::ifstream(summary));
  EXPECT_EQ(j["modes"]["kept"], 6);
  EXPECT_EQ(j["eigen"]["rigid_removed"], 6);
  for (const char* stage :
       {"read mesh", "check surface", "tetrahedralize", "assemble", "eigen-solve"})
    EXPECT_TRUE(j["seconds"].contains(stage)) << stage;
  EXPECT_NEAR(j["frequencies_hz"][0].get<double>(), 575.0, 6.0);

  r = run("info " + bank + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["modes"].size(), 6u);
  EXPECT_EQ(j["material"]["name"], "steel");
  const auto& m0 = j["modes"][0];
  EXPECT_NEAR(m0["t60_s"].get<double>() * m0["decay_per_s"].get<double>(), std::log(1000.0), 1e-9);
  r = run("info " + bank);
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("T60 (s)"), std::string::npos);

  const std::string scene = chladni::test::write_temp("chladni_cli_bank_scene.json", R"({
    "objects": [{"name": "bar", "soundbank": ")" + bank + R"("}],
    "events": [{"time": 0.01, "type": "impact", "object": "bar", "impulse": 0.01, "vertex": 3}],
    "duration": 1.0})");
  const std::string wav = chladni::test::temp_path("chladni_cli_bank.wav");
  r = run("render " + scene + " -o " + wav);
  ASSERT_EQ(r.code, 0) << r.output;
  const chladni::AudioBuffer a = chladni::read_audio(wav);
  float peak = 0;
  for (float x : a.samples) peak = std::max(peak, std::abs(x));
  EXPECT_GT(peak, 0.0f);

  // A corrupted bank is refused by render and info, naming the section.
  std::vector<char> bytes;
  {
    std::ifstream f(bank, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(f), {});
  }
  bytes[bytes.size() - 9] ^= 0x40;  // inside the last section (SHAP)
  const std::string bad = chladni::test::temp_path("chladni_cli_bad.chbank");
  std::ofstream(bad, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  r = run("info " + bad);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("section 'SHAP' checksum mismatch"), std::string::npos) << r.output;
}

TEST(CliPrecompute, BrokenMeshesExitWith2AndRepairGoesThrough) {
  Result r = run("precompute " CHLADNI_SOURCE_DIR "/meshes/broken/elephant_with_holes.obj -o " +
                 chladni::test::temp_path("chladni_e.chbank"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("not closed: 1353 boundary edges"), std::string::npos) << r.output;
  r = run("precompute " CHLADNI_SOURCE_DIR "/meshes/broken/teapot_solid_selfintersecting.obj -o " +
          chladni::test::temp_path("chladni_t.chbank"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("35 pairs of faces intersect"), std::string::npos) << r.output;
  // Read as centimetres the teapot is 17.6 cm long: repaired, meshed coarsely and solved.
  r = run("precompute " CHLADNI_SOURCE_DIR "/meshes/broken/teapot_solid_selfintersecting.obj -o " +
          chladni::test::temp_path("chladni_t.chbank") +
          " --unit cm --repair --order 1 --max-modes 4 --max-tet-volume 2e-6");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("repaired: self-intersections: 35 face pairs -> 0"), std::string::npos)
      << r.output;
}

TEST(CliPrecompute, BadArgumentsNameTheProblem) {
  const std::string out = chladni::test::temp_path("chladni_x.chbank");
  const std::string bar = CHLADNI_SOURCE_DIR "/meshes/bar.obj";
  Result r = run("precompute " + bar + " -o " + out + " --material unobtainium");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("unknown material 'unobtainium'; known: steel"), std::string::npos);
  r = run("precompute " + bar + " -o " + out + " --nu 0.5");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("Poisson's ratio"), std::string::npos);
  r = run("precompute " + bar + " -o " + out + " --damping rayleigh:1");
  EXPECT_EQ(r.code, 2);
  r = run("precompute " + bar + " -o " + out + " --order 3");
  EXPECT_EQ(r.code, 2);
  r = run("precompute " + bar + " -o " + out + " --max-freq nan");
  EXPECT_EQ(r.code, 2);
  r = run("precompute " + bar + " -o " + out + " --sample-rate 0");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--sample-rate"), std::string::npos);
  r = run("precompute " + bar + " -o " + out + " --unit furlong");
  EXPECT_EQ(r.code, 2);
  r = run("precompute /nonexistent.obj -o " + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("no such mesh file"), std::string::npos);
  r = run("materials");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("sl2016-porcelain:caughey"), std::string::npos);
}
