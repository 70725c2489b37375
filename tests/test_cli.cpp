// The chladni command end to end: exit codes, messages, the WAV it writes, bench's JSON.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chladni/core/audio_file.hpp"

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

std::string temp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / name).string();
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = temp(name);
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(Cli, RendersTheExampleSceneToAWav) {
  const std::string out = temp("chladni_cli_example.wav");
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
  const std::string scene = write_file("chladni_cli_bad.json", R"({
    "objects": [{"name": "a", "modes": [{"frequency": 440, "decay": 1, "amplitude": 1}]}],
    "events": [{"time": 0.1, "type": "impact", "object": "b", "impulse": 1}]})");
  const Result r = run("render " + scene + " -o " + temp("x.wav"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("$.events[0].object: unknown object 'b'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(scene), std::string::npos) << r.output;
}

TEST(Cli, BadArgumentsExitWith2) {
  EXPECT_EQ(run("render").code, 2);
  EXPECT_EQ(run("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " + temp("x.wav") +
                " --backend tpu")
                .code,
            2);
  EXPECT_EQ(run("render /nonexistent.json -o " + temp("x.wav")).code, 2);
  EXPECT_EQ(run("bench --modes 10,abc").code, 2);
  EXPECT_EQ(run("no-such-command").code, 2);
}

TEST(Cli, MissingVulkanDeviceFallsBackToCpuWithOneWarning) {
  // A selector that matches no device is how a machine without one looks to the backend.
  const Result r = run("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " +
                           temp("chladni_cli_fallback.wav") + " --backend gpu --quiet",
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
  const std::string json_path = temp("chladni_bench.json");
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
