// Every numeric option of every command, found in the command's own --help, given hostile
// values (NaN, infinities, zero, negative, tiny, huge, past 2^32) on top of a quick valid run:
// each must end with exit 0 or a clear exit 2 within a minute. A signal, an internal error (1),
// or a run past the limit fails. New options are covered as soon as --help shows them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <vector>

#include "cli_support.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using chladni::test::run_cli;

#ifndef CHLADNI_SANITIZED
const char* const kHostile[] = {"nan", "inf", "-inf", "-1", "0", "1e-300", "1e300", "4294967297"};
#else
// The sanitizer build runs each value in a process of about a third of a second, hundreds of
// them: one of each class there (the release build tries all eight for the exit codes).
const char* const kHostile[] = {"nan", "-1", "0", "1e300", "4294967297"};
#endif

// Inputs every command's quick run needs, made once.
const fs::path& inputs() {
  static const fs::path dir = [] {
    // Per process: ctest runs these tests side by side.
    const fs::path d = chladni::test::temp_path("chladni_hostile_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    std::string cube;
    for (int v = 0; v < 8; ++v)
      cube += "v " + std::to_string(0.1 * (v & 1)) + " " + std::to_string(0.1 * (v >> 1 & 1)) +
              " " + std::to_string(0.1 * (v >> 2 & 1)) + "\n";
    cube +=
        "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\n"
        "f 1 7 3\nf 2 4 8\nf 2 8 6\n";
    std::ofstream((d / "cube.obj").string()) << cube;
    std::ofstream((d / "points.txt").string()) << "0 0 1\n0.3 0.2 0.5\n";
    std::ofstream((d / "batch.json").string())
        << R"({"assets": [{"mesh": "cube.obj", "max-modes": 3, "no-transfer": true,
                           "max-tet-volume": 2e-4}]})";
    const std::string s = d.string();
    for (const std::string& setup :
         {"precompute " + s + "/cube.obj -o " + s +
              "/cube.chbank --max-modes 3 --transfer-method sources -q",
          "paper-gen flap -o " + s + "/anim --triangles 50 --duration 0.2",
          "paper-db generate -o " + s +
              "/db --variants 1 --clip-seconds 0.05 "
              "--friction-seconds 0.2"}) {
      const auto r = run_cli(setup);
      EXPECT_EQ(r.code, 0) << setup << "\n" << r.output;
    }
    return d;
  }();
  return dir;
}

// Numeric options listed by `chladni <command> --help`.
std::vector<std::string> numeric_options(const std::string& command) {
  const auto help = run_cli(command + " --help");
  EXPECT_EQ(help.code, 0) << help.output;
  std::vector<std::string> out;
  const std::regex line(R"(^\s+(?:-\w,)?(--[\w-]+)(?:,[-\w]+)?\s+(?:FLOAT|INT|UINT)\b)");
  std::istringstream in(help.output);
  for (std::string l; std::getline(in, l);) {
    std::smatch m;
    if (std::regex_search(l, m, line)) out.push_back(m[1]);
  }
  return out;
}

// `base` without `option` and its value.
std::string without(const std::string& base, const std::string& option) {
  std::istringstream in(base);
  std::string out, tok;
  while (in >> tok) {
    if (tok == option) {
      in >> tok;
      continue;
    }
    out += tok + " ";
  }
  return out;
}

void check_command(const std::string& command, const std::string& base, std::size_t at_least) {
  const std::vector<std::string> options = numeric_options(command);
  EXPECT_GE(options.size(), at_least) << command << ": --help lists fewer numeric options";
  for (const std::string& opt : options)
    for (const char* value : kHostile) {
      const std::string args = command + " " + without(base, opt) + opt + " " + value;
      // Hundreds of short runs: under the sanitizer build, without the lavapipe preload and leak
      // check that cost each process about a second (other tests keep them); ASan and UBSan stay.
      const auto r =
          run_cli(args, "env -u LD_PRELOAD ASAN_OPTIONS=detect_leaks=0:abort_on_error=1", 60);
      // 3: over the memory budget (a tiny --max-memory).
      EXPECT_TRUE(r.code == 0 || r.code == 2 || r.code == 3)
          << "chladni " << args << "\nexit " << r.code << "\n"
          << r.output.substr(0, 2000);
      if (r.code != 0) {
        EXPECT_FALSE(r.output.empty()) << args;  // says why
      }
    }
}

}  // namespace

// The cube's modes lie near 17 kHz, where the automatic transfer would take the wave solve (a
// minute under the sanitizers, for each of the hundred runs); the equivalent-source fit takes the
// same numeric options (order, sources, sound speed, air density) in well under a second.
TEST(CliHostile, Precompute) {
  const std::string d = inputs().string();
  check_command("precompute",
                d + "/cube.obj -o " + d +
                    "/p.chbank --max-modes 3 --max-tet-volume 2e-4 --transfer-method sources -q",
                15);
}

TEST(CliHostile, Radiate) {
  const std::string d = inputs().string();
  check_command("radiate",
                d + "/cube.obj --freq 1000 --pattern uniform --points " + d + "/points.txt", 5);
}

TEST(CliHostile, Render) {
  const std::string d = inputs().string();
  check_command("render", CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " + d + "/r.wav -q", 5);
}

TEST(CliHostile, Shake) {
  const std::string d = inputs().string();
  check_command("shake", "guiro -o " + d + "/s.wav --duration 0.05 --bank " + d + "/cube.chbank -q",
                10);
}

TEST(CliHostile, Paper) {
  const std::string d = inputs().string();
  check_command("paper-gen", "flap -o " + d + "/anim2 --triangles 50 --duration 0.2", 4);
  check_command("paper", d + "/anim/flap.json -o " + d + "/p.wav --db " + d + "/db", 4);
  check_command("paper-db generate",
                "-o " + d + "/db2 --variants 1 --clip-seconds 0.02 --friction-seconds 0.11", 4);
}

TEST(CliHostile, Batch) {
  const std::string d = inputs().string();
  check_command("batch", d + "/batch.json -o " + d + "/batch_out --force -q", 3);
}

TEST(CliHostile, Report) {
  const std::string d = inputs().string();
  check_command("report", d + "/cube.chbank -o " + d + "/report", 4);
}

TEST(CliHostile, Bench) {
  check_command("bench", "--modes 64 --seconds 0.01 --backend cpu", 3);
}

// A single tetrahedron (a volume bound larger than the solid keeps it one) has 24 elastic modes
// (quadratic elements: 10 nodes, 30 DOFs, six rigid):
// the first few are found (densely, where Lanczos would need more vectors than exist) and asking
// for more than there are is a clear refusal, not "did not converge".
TEST(CliHostile, TinySolidsGetTheirModesOrAClearRefusal) {
  const std::string d = inputs().string();
  const std::string tet = d + "/tet.obj";
  std::ofstream(tet) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n"
                        "f 2 3 4\n";
  auto r = run_cli("precompute " + tet + " -o " + d +
                   "/tet.chbank --max-modes 5 --no-transfer --max-tet-volume 10");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("tetrahedra 1 "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("5 elastic modes"), std::string::npos) << r.output;
  r = run_cli("precompute " + tet + " -o " + d +
              "/tet.chbank --max-modes 30 --no-transfer --max-tet-volume 10");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("has only 24 elastic modes"), std::string::npos) << r.output;
  r = run_cli("precompute " + d + "/cube.obj -o " + d +
              "/c.chbank --order 1 --max-modes 5 --tolerance 0.05 "
              "--no-transfer");
  EXPECT_EQ(r.code, 0) << r.output;
}

// Scale the other way. A 200 m bar has 21 modes below 20 Hz: asked for 20, it gets 20 above,
// the ones below dropped. A 200 km one (a file in micrometres read as metres) has none in the
// band at all: refused at once, naming the unit, where the shift-invert once crowded its modes
// (all below a millihertz) together and never converged.
TEST(CliHostile, HugeSolidsKeepTheModesAskedForOrAreRefusedNamingTheUnit) {
  const std::string d = inputs().string(), bar = CHLADNI_SOURCE_DIR "/meshes/bar.obj";
  auto r = run_cli("precompute " + bar + " -o " + d +
                   "/huge.chbank --scale 1000 --max-modes 20 --no-transfer");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("modes kept 20; dropped: 0 overdamped, 21 below 20 Hz"),
            std::string::npos)
      << r.output;
  r = run_cli("precompute " + bar + " -o " + d +
              "/huger.chbank --scale 1000000 --max-modes 20 --no-transfer");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("no mode lies in [20 Hz, 20000 Hz]"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check --unit/--scale"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(d + "/huger.chbank"));
}
