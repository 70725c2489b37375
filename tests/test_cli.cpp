// The chladni command end to end: exit codes, messages, the WAV it writes, bench's JSON.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chladni/core/audio_file.hpp"
#include "cli_support.hpp"
#include "test_support.hpp"

namespace {

using Result = chladni::test::CliResult;

Result run(const std::string& args, const std::string& env = "") {
  return chladni::test::run_cli(args, env);
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
  for (const auto& [bad, message] :
       {std::pair<std::string, std::string>{" --backend tpu", "--backend: unknown backend 'tpu'"},
        {" --isa sse", "--isa: unknown instruction set 'sse'"}}) {
    const Result r = run("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " +
                         chladni::test::temp_path("x.wav") + bad);
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
  }
  EXPECT_EQ(run("render /nonexistent.json -o " + chladni::test::temp_path("x.wav")).code, 2);
  EXPECT_EQ(run("bench --modes 10,abc").code, 2);
  EXPECT_EQ(run("no-such-command").code, 2);
  // Numbers a user can type are bounded before any work: thread counts, and levels that would
  // turn every sample into NaN.
  const std::string scene =
      CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " + chladni::test::temp_path("x.wav");
  for (const char* bad : {" --threads 100000", " --threads -1", " --normalize inf",
                          " --normalize nan", " --normalize 1e308", " --normalize abc"}) {
    const Result r = run("render " + scene + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find(std::string(bad).substr(1, std::string(bad).find(' ', 1) - 1)),
              std::string::npos)
        << "the message names the option: " << r.output;
  }
  EXPECT_EQ(run("shake maraca -o " + chladni::test::temp_path("x.wav") + " --threads 100000").code,
            2);
  EXPECT_EQ(run("bench --threads 100000").code, 2);
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
  // Not a terminal: long stages say how far they are, as plain lines, with the time left.
  EXPECT_NE(r.output.find("  transfer: 50 % ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" s left)\n"), std::string::npos) << r.output;
  nlohmann::json j = nlohmann::json::parse(std::ifstream(summary));
  EXPECT_EQ(j["modes"]["kept"], 6);
  EXPECT_EQ(j["eigen"]["rigid_removed"], 6);
  for (const char* stage :
       {"read mesh", "check surface", "tetrahedralize", "assemble", "eigen-solve"})
    EXPECT_TRUE(j["seconds"].contains(stage)) << stage;
  // Each stage's peak resident memory, none above the process's.
  for (const auto& [stage, mb] : j["peak_memory_mb"].items()) {
    EXPECT_TRUE(j["seconds"].contains(stage)) << stage;
    EXPECT_GT(mb.get<double>(), 1.0) << stage;
    EXPECT_LE(mb.get<double>(), j["peak_rss_mb"].get<double>() + 1e-9) << stage;
  }
  EXPECT_TRUE(j["peak_memory_mb"].contains("eigen-solve")) << j["peak_memory_mb"].dump();
  EXPECT_NE(r.output.find("peak memory: read mesh "), std::string::npos) << r.output;
  EXPECT_NEAR(j["frequencies_hz"][0].get<double>(), 575.0, 6.0);
  // The symbolic analysis reports the factor before it is computed.
  EXPECT_GT(j["eigen"]["factor_nonzeros"].get<double>(), double(j["volume_mesh"]["dofs"]));
  EXPECT_GT(j["eigen"]["factor_bytes"].get<double>(),
            8 * j["eigen"]["factor_nonzeros"].get<double>() - 1);
  EXPECT_GT(j["eigen"]["factor_flops"].get<double>(), 0.0);
  // And predicts its time from the flops and the BLAS's measured rate: seconds for the bar.
  EXPECT_GT(j["eigen"]["factor_seconds_estimate"].get<double>(), 0.0);
  EXPECT_LT(j["eigen"]["factor_seconds_estimate"].get<double>(), 60.0);

  r = run("info " + bank + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["modes"].size(), 6u);
  EXPECT_EQ(j["material"]["name"], "steel");
  ASSERT_TRUE(j["transfer"].is_object()) << j.dump();
  EXPECT_GT(j["transfer"]["radius_m"].get<double>(), 0.15);
  for (const auto& m : j["modes"]) {
    EXPECT_GE(m["transfer"]["order"].get<int>(), 0);
    EXPECT_GT(m["transfer"]["sources"].get<int>(), 0);
    EXPECT_EQ(m["transfer"]["poor_fit"].get<bool>(),
              m["transfer"]["held_out_error"].get<double>() > 0.3);
  }
  const auto& m0 = j["modes"][0];
  EXPECT_NEAR(m0["t60_s"].get<double>() * m0["decay_per_s"].get<double>(), std::log(1000.0), 1e-9);
  r = run("info " + bank);
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("T60 (s)"), std::string::npos);
  EXPECT_NE(r.output.find("held-out"), std::string::npos);

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
  bytes[bytes.size() - 9] ^= 0x40;  // inside the last section (XFER)
  const std::string bad = chladni::test::temp_path("chladni_cli_bad.chbank");
  std::ofstream(bad, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  r = run("info " + bad);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("section 'XFER' checksum mismatch"), std::string::npos) << r.output;
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
          " --unit cm --repair --order 1 --max-modes 4 --max-tet-volume 2e-6 --no-transfer");
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
  // A non-finite material constant is refused, not silently replaced by the preset's.
  for (const char* bad :
       {" --E nan", " --nu nan", " --rho inf", " --E -2e11", " --threads 100000"}) {
    r = run("precompute " + bar + " -o " + out + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find(std::string(bad).substr(1, std::string(bad).find(' ', 1) - 1)),
              std::string::npos)
        << r.output;
  }
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
  EXPECT_NE(r.output.find("mesh /nonexistent.obj: cannot open"), std::string::npos) << r.output;
  r = run("materials");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("sl2016-porcelain:caughey"), std::string::npos);
}

// A problem larger than --max-memory is refused after the symbolic analysis, before the
// factorization, with what it would need; an existing output is left as it was.
TEST(CliPrecompute, MemoryBudgetRefusesBeforeTheFactorization) {
  const std::string out = chladni::test::write_temp("chladni_budget.chbank", "keep");
  const std::string bar = CHLADNI_SOURCE_DIR "/meshes/bar.obj";
  Result r = run("precompute " + bar + " -o " + out +
                 " --max-modes 6 --max-tet-volume 1e-6 --max-memory 0.001");
  EXPECT_EQ(r.code, 3) << r.output;  // over the budget, not bad input
  EXPECT_NE(r.output.find("more than the memory budget of 0.00 GB"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nnz(L)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--max-memory"), std::string::npos) << r.output;
  EXPECT_EQ(chladni::test::read_file(out), "keep");
  // K, M and the copies the factorization makes count too (about 30 MB here): the factor and
  // the basis alone would fit in 60 MB.
  r = run("precompute " + bar + " -o " + out + " --max-modes 6 --max-memory 0.06");
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("the matrices and their copies while it is computed: 0.03 GB"),
            std::string::npos)
      << r.output;
  // The boundary-element transfer is held to the same budget: the eigen-solve (linear
  // elements: about 10 MB) fits in 50 MB, the BEM system on the bar's own 1,968 triangles
  // (about 100 MB) does not.
  r = run("precompute " + bar + " -o " + out +
          " --max-modes 3 --order 1 --transfer-method bem --max-memory 0.05");
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find(bar + ": transfer: boundary elements on the 1968 surface triangles need"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--transfer-method auto or sources"), std::string::npos) << r.output;
  EXPECT_EQ(chladni::test::read_file(out), "keep");
  r = run("precompute " + bar + " -o " + out + " --max-memory nan");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--max-memory"), std::string::npos) << r.output;
}

// Every mode below 20 kHz of Spot as shipped (1.7 m) would need a mesh of about 600,000
// tetrahedra, minutes of meshing, and a factor far over the budget: refused from coarser meshes
// before that meshing, with the lower bound, how many modes the band holds, and the output kept.
TEST(CliPrecompute, MemoryBudgetRefusesBeforeMeshing) {
  const std::string out = chladni::test::write_temp("chladni_budget_mesh.chbank", "keep");
  Result r = run("precompute " CHLADNI_SOURCE_DIR "/meshes/spot.obj -o " + out + " --max-memory 4");
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("the eigen-solve would need at least"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("a lower bound found before meshing"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("modes lie below 20000 Hz: ask for the first N with --max-modes"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("[4] assemble"), std::string::npos) << r.output;
  EXPECT_EQ(chladni::test::read_file(out), "keep");
}

// Outputs are checked before the work that fills them, and replaced atomically: a bad path
// fails at once with exit 2 and leaves what was there; a good run leaves no temporaries behind.
TEST(CliOutputs, CheckedFirstAndReplacedAtomically) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(chladni::test::temp_path("chladni_outputs"));
  fs::remove_all(dir);
  fs::create_directories(dir / "a_folder");
  const std::string bank = (dir / "bank.chbank").string();
  std::ofstream(bank) << "keep";
  const std::string bar = CHLADNI_SOURCE_DIR "/meshes/bar.obj";
  Result r = run("precompute " + bar + " -o " + bank + " --max-modes 2 --max-tet-volume 1e-6 " +
                 "--no-transfer --json " + (dir / "a_folder").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--json " + (dir / "a_folder").string() + ": is a directory"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(chladni::test::read_file(bank), "keep");
  r = run("precompute " + bar + " -o " + (dir / "a_folder").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("is a directory"), std::string::npos) << r.output;
  r = run("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " +
          (dir / "missing" / "x.wav").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  r = run("shake maraca --duration 0.2 -o " + (dir / "m.wav").string() + " --spectrogram " +
          (dir / "a_folder").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(fs::exists(dir / "m.wav"));
  // A good run replaces the bank and the WAV in one step each and leaves nothing else.
  r = run("precompute " + bar + " -o " + bank + " --max-modes 2 --max-tet-volume 1e-6 " +
          "--no-transfer -q --json " + (dir / "s.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  r = run("shake maraca --duration 0.2 -o " + (dir / "m.wav").string() + " --spectrogram " +
          (dir / "m.png").string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    files += e.is_regular_file();
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
  }
  EXPECT_EQ(files, 4u);  // bank, s.json, m.wav, m.png
  EXPECT_NE(chladni::test::read_file(bank), "keep");
  fs::remove_all(dir);
}

TEST(CliPrecompute, NoTransferLeavesXferOut) {
  const std::string bank = chladni::test::temp_path("chladni_cli_bar_nox.chbank");
  Result r = run("precompute " CHLADNI_SOURCE_DIR "/meshes/bar.obj -o " + bank +
                 " --max-modes 2 --max-tet-volume 1e-6 --no-transfer -q");
  ASSERT_EQ(r.code, 0) << r.output;
  r = run("info " + bank + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(nlohmann::json::parse(r.output)["transfer"].is_null());
}

namespace {

// bar.obj's first 20 modes with `env` before the command: its --json summary.
nlohmann::json bar_summary(const std::string& name, const std::string& env) {
  const std::string json = chladni::test::temp_path(name + ".json");
  const Result r = run("precompute " CHLADNI_SOURCE_DIR "/meshes/bar.obj -o " +
                           chladni::test::temp_path(name + ".chbank") +
                           " --max-modes 20 --no-transfer -q --json " + json,
                       env);
  EXPECT_EQ(r.code, 0) << r.output;
  return nlohmann::json::parse(std::ifstream(json));
}

}  // namespace

// Huge pages are an allocation hint only: with them turned off the modes are the same.
TEST(CliPrecompute, HugePagesChangeNoMode) {
  std::vector<double> hz[2];
  for (int off : {0, 1})
    hz[off] = bar_summary("chladni_cli_huge", off ? "CHLADNI_HUGE_PAGES=0" : "")["frequencies_hz"]
                  .get<std::vector<double>>();
  ASSERT_EQ(hz[0].size(), 20u);
  ASSERT_EQ(hz[1].size(), 20u);
  for (std::size_t i = 0; i < 20; ++i) EXPECT_NEAR(hz[0][i], hz[1][i], 1e-9 * hz[0][i]) << i;
}

// Where OpenBLAS does not know the CPU it runs generic SSE3 kernels; the CLI starts again with
// OPENBLAS_CORETYPE naming the AVX2 or AVX-512 ones. The user's own setting stands, and the
// kernels change no mode.
TEST(CliPrecompute, BlasKernelsSuitTheCpuAndChangeNoMode) {
  std::vector<double> hz[2];
  std::string kernels[2];
  for (int forced : {0, 1}) {
    const nlohmann::json j = bar_summary(
        "chladni_cli_blas", forced ? "OPENBLAS_CORETYPE=Prescott" : "env -u OPENBLAS_CORETYPE");
    hz[forced] = j["frequencies_hz"].get<std::vector<double>>();
    kernels[forced] = j["eigen"]["blas_kernels"].get<std::string>();
  }
  if (kernels[1].empty()) GTEST_SKIP() << "the BLAS is not OpenBLAS";
  EXPECT_EQ(kernels[1], "Prescott");
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    for (const char* generic : {"Prescott", "Core2", "Nehalem", "Unknown"}) {
      EXPECT_NE(kernels[0], generic);
    }
  }
  ASSERT_EQ(hz[0].size(), 20u);
  ASSERT_EQ(hz[1].size(), 20u);
  for (std::size_t i = 0; i < 20; ++i) EXPECT_NEAR(hz[0][i], hz[1][i], 1e-9 * hz[0][i]) << i;
}

// radiate on the bundled sphere: the JSON pressures against the exact solution
// p = i rho0 c U h_l(kr) / h_l'(ka) P_l(cos t), via the sources and via the multipole series.
TEST(CliRadiate, SphereHarmonicMatchesTheExactSolution) {
  const std::string pts = chladni::test::write_temp("chladni_radiate_pts.txt",
                                                    "# x y z\n0 0 0.25\n0.2 0.1 -0.3\n0.5 0 0.1\n");
  const std::string json = chladni::test::temp_path("chladni_radiate.json");
  const double a = 0.1, f = 900, c = 343.0, rho = 1.204, k = 2 * M_PI * f / c;
  for (const std::string via : {"surface", "multipole"})
    for (const std::string method : {"sources", "bem", "bem --backend gpu"}) {
      const Result r = run("radiate " CHLADNI_SOURCE_DIR
                           "/meshes/sphere.obj --freq 900 --pattern "
                           "sphere-harmonic:l=2,m=0 --points " +
                           pts + " --json " + json + " --via " + via + " --method " + method);
      ASSERT_EQ(r.code, 0) << r.output;
      const nlohmann::json j = nlohmann::json::parse(std::ifstream(json));
      EXPECT_EQ(j["method"], method.substr(0, method.find(' ')));
      ASSERT_EQ(j["points"].size(), 3u);
      for (const auto& p : j["points"]) {
        const double x = p["x"], y = p["y"], z = p["z"];
        const double r0 = std::sqrt(x * x + y * y + z * z), ct = z / r0;
        const std::complex<double> h =
            std::sph_bessel(2, k * r0) + std::complex<double>(0, 1) * std::sph_neumann(2, k * r0);
        // h_2'(x) = h_1(x) - 3/x h_2(x)
        const double ka = k * a;
        const std::complex<double> h1a =
            std::sph_bessel(1, ka) + std::complex<double>(0, 1) * std::sph_neumann(1, ka);
        const std::complex<double> h2a =
            std::sph_bessel(2, ka) + std::complex<double>(0, 1) * std::sph_neumann(2, ka);
        const std::complex<double> exact =
            std::complex<double>(0, rho * c) * h / (h1a - 3.0 / ka * h2a) * std::legendre(2, ct);
        const std::complex<double> got(p["pressure"]["re"].get<double>(),
                                       p["pressure"]["im"].get<double>());
        EXPECT_LT(std::abs(got - exact), 0.02 * std::abs(exact))
            << method << " " << via << " at " << x << " " << y << " " << z;
      }
    }
}

TEST(CliRadiate, BadInputNamesFileAndLine) {
  const std::string sphere = CHLADNI_SOURCE_DIR "/meshes/sphere.obj";
  const std::string pts =
      chladni::test::write_temp("chladni_radiate_bad_pts.txt", "0 0 1\n0 nan 2\n");
  Result r = run("radiate " + sphere + " --freq 500 --pattern uniform --points " + pts);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("chladni_radiate_bad_pts.txt:2: 'nan' is not a finite number"),
            std::string::npos)
      << r.output;
  const std::string good = chladni::test::write_temp("chladni_radiate_good_pts.txt", "0 0 1\n");
  const std::string vel = chladni::test::write_temp("chladni_radiate_vel.txt", "1\n0.5 0.25\n");
  r = run("radiate " + sphere + " --freq 500 --velocity " + vel + " --points " + good);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("2 velocity values, but"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("has 2562 vertices"), std::string::npos) << r.output;
  r = run("radiate " + sphere + " --freq 500 --pattern uniform --method fmm --points " + good);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--method: unknown method 'fmm' (auto, bem, wave, sources)"),
            std::string::npos)
      << r.output;
  r = run("radiate " + sphere + " --freq 500 --pattern uniform --method wave --points " + good);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("radiate takes auto, bem or sources"), std::string::npos) << r.output;
  r = run("radiate " + sphere + " --freq 500 --pattern sphere-harmonic:l=2,m=5 --points " + good);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("|m| <= l"), std::string::npos) << r.output;
  r = run("radiate " CHLADNI_SOURCE_DIR
          "/meshes/broken/elephant_with_holes.obj --freq 500 --pattern uniform --points " +
          good);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("boundary edges"), std::string::npos) << r.output;
}

TEST(CliShake, WritesTheInstrumentAndTheSameSoundOnBothBackends) {
  const std::string cpu = chladni::test::temp_path("chladni_shake_cpu.wav"),
                    gpu = chladni::test::temp_path("chladni_shake_gpu.wav");
  const Result r =
      run("shake tambourine -o " + cpu + " --duration 1 --shakes-per-second 3 --seed 4");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("collisions"), std::string::npos) << r.output;
  const Result g = run("shake tambourine -o " + gpu +
                       " --duration 1 --shakes-per-second 3 --seed 4 --backend gpu");
  ASSERT_EQ(g.code, 0) << g.output;
  const chladni::AudioBuffer a = chladni::read_audio(cpu), b = chladni::read_audio(gpu);
  EXPECT_EQ(a.sample_rate, 48000);
  EXPECT_EQ(a.channels, 1);
  ASSERT_EQ(a.frames(), 48000u);
  ASSERT_EQ(b.frames(), a.frames());
  const double peak = chladni::test::max_abs(a.samples);
  EXPECT_GT(peak, 0.0);
  EXPECT_LT(chladni::test::max_diff(a.samples, b.samples), 1e-4 * peak);
  // Several voices are spread over a stereo field.
  const Result v = run("shake maraca -o " + cpu + " --duration 0.5 --voices 3 --quiet");
  ASSERT_EQ(v.code, 0) << v.output;
  EXPECT_EQ(chladni::read_audio(cpu).channels, 2);
  EXPECT_NE(run("shake --list").output.find("sleighbells"), std::string::npos);
}

TEST(CliShake, ParticlesOnASoundbankAndBadInputExitWith2) {
  const std::string bank = chladni::test::temp_path("chladni_shake_bar.chbank");
  const std::string out = chladni::test::temp_path("chladni_shake_bank.wav");
  ASSERT_EQ(
      run("precompute " CHLADNI_SOURCE_DIR "/meshes/bar.obj -o " + bank + " --no-transfer --quiet")
          .code,
      0);
  const Result r = run("shake gravel -o " + out + " --bank " + bank + " --duration 0.5");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find(bank), std::string::npos) << r.output;
  EXPECT_GT(chladni::test::max_abs(chladni::read_audio(out).samples), 0.0);

  const Result unknown = run("shake kazoo -o " + out);
  EXPECT_EQ(unknown.code, 2);
  EXPECT_NE(unknown.output.find("unknown instrument 'kazoo' (known: maraca"), std::string::npos)
      << unknown.output;
  const Result nan = run("shake maraca -o " + out + " --duration nan");
  EXPECT_EQ(nan.code, 2);
  EXPECT_NE(nan.output.find("--duration"), std::string::npos) << nan.output;
  EXPECT_EQ(run("shake maraca -o " + out + " --particles -4").code, 2);
  EXPECT_EQ(run("shake maraca -o " + out + " --shakes-per-second 0").code, 2);
  EXPECT_EQ(run("shake maraca -o " + out + " --energy 3").code, 2);
  const std::string junk = chladni::test::write_temp("chladni_junk.chbank", "not a soundbank");
  const Result bad = run("shake gravel -o " + out + " --bank " + junk);
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.output.find(junk), std::string::npos) << bad.output;
  EXPECT_EQ(run("shake maraca").code, 2);  // no output file
}
