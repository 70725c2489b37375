// The batch driver end to end: bad assets skipped, reruns that skip what is current, a SIGKILL
// midway then a resume, memory shared and retried alone, MPI ranks (manifests and jobs:
// test_batch_manifest.cpp).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "batch_fixtures.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/precompute/batch.hpp"
#include "cli_support.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
namespace batch = chladni::precompute::batch;
using chladni::test::run_cli;

using namespace chladni::test::batch_fixtures;

namespace {

// Status per asset name from a batch summary.
std::map<std::string, std::string> statuses(const fs::path& summary) {
  std::map<std::string, std::string> out;
  const nlohmann::json s = read_json(summary);
  for (const auto& row : s["assets"])
    out[row["asset"].get<std::string>()] = row["status"].get<std::string>();
  return out;
}

}  // namespace

// One bad asset is reported and skipped, the others go on; the exit code says not all
// succeeded. A rerun skips what is current and redoes what changed.
TEST(BatchCli, BadAssetsSkippedAndReRunsRedoOnlyWhatChanged) {
  const fs::path d = fresh_dir("cli");
  write_box(d / "small.obj", 0.08, 0.1, 0.12);
  write_box(d / "large.obj", 0.1, 0.13, 0.15);
  write_box(d / "open.obj", 0.1, 0.1, 0.1, true);
  const auto write_manifest = [&](int modes) {
    std::ofstream(d / "m.json") << R"({"output_dir": "banks",
      "defaults": {"max-modes": 4, "no-transfer": true},
      "assets": ["small.obj", "open.obj", "missing.obj", ")"
                                << CHLADNI_SOURCE_DIR << R"(/meshes/broken/*.obj",
                 {"mesh": "large.obj", "material": "brass", "max-modes": )"
                                << modes << "}]}";
  };
  write_manifest(5);
  chladni::test::CliResult r = run_cli("batch " + (d / "m.json").string() + " -j 2");
  EXPECT_EQ(r.code, 2) << r.output;
  const fs::path summary = d / "banks/batch-summary.json";
  auto st = statuses(summary);
  EXPECT_EQ(st["small"], "ok");
  EXPECT_EQ(st["large"], "ok");
  EXPECT_EQ(st["open"], "bad input");
  EXPECT_EQ(st["missing"], "bad input");
  EXPECT_EQ(st["elephant_with_holes"], "bad input");  // the bundled broken meshes
  EXPECT_EQ(st["teapot_solid_selfintersecting"], "bad input");
  const nlohmann::json rows = read_json(summary)["assets"];
  EXPECT_NE(rows[1]["error"].get<std::string>().find("open.obj"), std::string::npos);
  EXPECT_NE(rows[2]["error"].get<std::string>().find("missing.obj"), std::string::npos);
  EXPECT_EQ(rows[5]["asset"], "large");
  EXPECT_EQ(rows[5]["modes"], 5);
  EXPECT_GT(rows[5]["peak_memory_mb"].get<double>(), 1.0);
  EXPECT_NE(r.output.find("bad input"), std::string::npos) << r.output;
  const chladni::Soundbank large = chladni::read_soundbank((d / "banks/large.chbank").string());
  EXPECT_EQ(large.mode_count(), 5u);
  EXPECT_NE(large.material.name.find("brass"), std::string::npos);
  EXPECT_EQ(chladni::read_soundbank((d / "banks/small.chbank").string()).mode_count(), 4u);
  const auto small_time = fs::last_write_time(d / "banks/small.chbank");

  write_manifest(6);
  r = run_cli("batch " + (d / "m.json").string() + " -j 2");
  EXPECT_EQ(r.code, 2) << r.output;
  st = statuses(summary);
  EXPECT_EQ(st["small"], "current");
  EXPECT_EQ(st["large"], "ok");
  EXPECT_EQ(fs::last_write_time(d / "banks/small.chbank"), small_time);
  EXPECT_EQ(chladni::read_soundbank((d / "banks/large.chbank").string()).mode_count(), 6u);

  // --force redoes it all; --dry-run says what would run and writes nothing.
  r = run_cli("batch " + (d / "m.json").string() + " --dry-run");
  EXPECT_NE(r.output.find("small  "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("current"), std::string::npos) << r.output;
  r = run_cli("batch " + (d / "m.json").string() + " --force -j 2 -q");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_EQ(statuses(summary)["small"], "ok");
  EXPECT_TRUE(r.output.empty()) << r.output;
}

// A batch killed midway leaves only valid soundbanks (each written to a temporary and renamed)
// and the rerun finishes the rest without redoing what was done.
TEST(BatchCli, KilledMidwayResumesWithEveryOutputValid) {
  const fs::path d = fresh_dir("kill");
  std::string list;
  const int n = 6;
  for (int i = 0; i < n; ++i) {
    const std::string name = "box" + std::to_string(i);
    write_box(d / (name + ".obj"), 0.1 + 0.01 * i, 0.1, 0.11);
    list += std::string(i ? ", " : "") + "\"" + name + ".obj\"";
  }
  std::ofstream(d / "m.json") << R"({"output_dir": "banks", "defaults": {"max-modes": 6,
    "no-transfer": true}, "assets": [)"
                              << list << "]}";
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    const std::string m = (d / "m.json").string();
    ::execl(CHLADNI_EXE, CHLADNI_EXE, "batch", m.c_str(), "-j", "1", nullptr);
    ::_exit(127);
  }
  ASSERT_GT(pid, 0);
  const auto banks = [&] {
    std::set<std::string> out;
    for (int i = 0; i < n; ++i)
      if (fs::exists(d / "banks" / ("box" + std::to_string(i) + ".chbank")))
        out.insert("box" + std::to_string(i));
    return out;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (banks().size() < 2 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the batch ended before it could be killed";
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // its child dies with it
  const std::set<std::string> done = banks();
  ASSERT_GE(done.size(), 2u);
  ASSERT_LT(done.size(), std::size_t(n)) << "all assets finished before the kill";
  for (const std::string& name : done)
    EXPECT_NO_THROW(chladni::read_soundbank((d / "banks" / (name + ".chbank")).string())) << name;

  const chladni::test::CliResult r = run_cli("batch " + (d / "m.json").string() + " -j 1");
  EXPECT_EQ(r.code, 0) << r.output;
  const auto st = statuses(d / "banks/batch-summary.json");
  for (int i = 0; i < n; ++i) {
    const std::string name = "box" + std::to_string(i);
    EXPECT_EQ(st.at(name), done.count(name) ? "current" : "ok") << name;
    EXPECT_EQ(chladni::read_soundbank((d / "banks" / (name + ".chbank")).string()).mode_count(),
              6u);
  }
  for (const auto& e : fs::directory_iterator(d / "banks"))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

// Each job gets its share of --max-memory; an asset that does not fit its share is refused
// (exit 3) and run again alone with the whole budget, and succeeds.
TEST(BatchCli, AssetOverItsShareIsRetriedAlone) {
  const fs::path d = fresh_dir("memory");
  write_box(d / "a.obj", 0.1, 0.12, 0.14);
  write_box(d / "b.obj", 0.1, 0.12, 0.14001);
  // What the eigen-solve needs besides the Lanczos basis, from a plain precompute's summary
  // (the basis adapts to what the budget leaves).
  chladni::test::CliResult r =
      run_cli("precompute " + (d / "a.obj").string() + " -o " + (d / "probe.chbank").string() +
              " --max-modes 4 --no-transfer --max-tet-volume 5e-6 -q --json " +
              (d / "probe.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json probe = read_json(d / "probe.json")["eigen"];
  const double need = probe["factor_bytes"].get<double>() + probe["matrix_bytes"].get<double>();
  ASSERT_GT(need, 0);
  r = run_cli("precompute " + (d / "a.obj").string() + " -o " + (d / "p2.chbank").string() +
              " --max-modes 4 --no-transfer --max-tet-volume 5e-6 -q --max-memory " +
              std::to_string(0.6 * need / 1e9));
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("more than the memory budget"), std::string::npos) << r.output;

  std::ofstream(d / "m.json") << R"({"defaults": {"max-modes": 4, "no-transfer": true,
    "max-tet-volume": 5e-6}, "assets": ["a.obj", "b.obj"]})";
  r = run_cli("batch " + (d / "m.json").string() + " -j 2 --max-memory " +
              std::to_string(1.6 * need / 1e9));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("will retry alone"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("alone, with the whole memory budget"), std::string::npos) << r.output;
  const auto st = statuses(d / "batch-summary.json");
  EXPECT_EQ(st.at("a"), "ok");
  EXPECT_EQ(st.at("b"), "ok");
  // Over budget even alone: reported once, not retried again (the batch ends).
  fs::remove(d / "a.chbank"), fs::remove(d / "b.chbank");
  r = run_cli("batch " + (d / "m.json").string() + " -j 2 --max-memory " +
              std::to_string(0.6 * need / 1e9));
  EXPECT_NE(r.code, 0) << r.output;
  const auto over = statuses(d / "batch-summary.json");
  EXPECT_NE(over.at("a"), "ok");
  EXPECT_NE(over.at("b"), "ok");
  std::size_t retries = 0;
  for (std::size_t p = 0; (p = r.output.find("will retry alone", p)) != std::string::npos; ++p)
    ++retries;
  EXPECT_EQ(retries, 2u) << r.output;
}

#ifdef CHLADNI_MPIEXEC
// The same batch under mpirun with 2 and 3 ranks: every asset runs once, on some rank, and the
// summary gathered on rank 0 says which; the broken mesh fails cleanly.
TEST(BatchMpi, TwoAndThreeRanksShareTheAssets) {
  for (int ranks : {2, 3}) {
    const fs::path d = fresh_dir("mpi" + std::to_string(ranks));
    std::string list = "\"open.obj\"";
    write_box(d / "open.obj", 0.1, 0.1, 0.1, true);
    for (int i = 0; i < 5; ++i) {
      write_box(d / ("box" + std::to_string(i) + ".obj"), 0.1 + 0.01 * i, 0.1, 0.11);
      list += ", \"box" + std::to_string(i) + ".obj\"";
    }
    std::ofstream(d / "m.json") << R"({"defaults": {"max-modes": 4, "no-transfer": true},
      "assets": [)" << list << "]}";
    const std::string cmd = std::string(CHLADNI_MPIEXEC) +
                            " --oversubscribe --allow-run-as-root -np " + std::to_string(ranks) +
                            " " + CHLADNI_EXE + " batch " + (d / "m.json").string() + " -j 1 2>&1";
    // Containers often forbid the cross-memory attach Open MPI's shared-memory transport tries
    // first; its messages here are small, so plain copies do.
    FILE* p = popen(("ASAN_OPTIONS=detect_leaks=0 OMPI_MCA_btl_vader_single_copy_mechanism=none "
                     "timeout -k 5 300 " +
                     cmd)
                        .c_str(),
                    "r");
    std::string out;
    char buf[4096];
    while (std::size_t k = std::fread(buf, 1, sizeof buf, p)) out.append(buf, k);
    const int status = pclose(p);
    EXPECT_EQ(WEXITSTATUS(status), 2) << out;  // the open box is bad input
    const nlohmann::json s = read_json(d / "batch-summary.json");
    EXPECT_EQ(s["ranks"], ranks);
    std::set<int> used;
    for (const auto& row : s["assets"]) {
      const std::string name = row["asset"];
      if (name == "open") {
        EXPECT_EQ(row["status"], "bad input");
        continue;
      }
      EXPECT_EQ(row["status"], "ok") << name << "\n" << out;
      EXPECT_EQ(row["modes"], 4);
      used.insert(row["rank"].get<int>());
      EXPECT_EQ(chladni::read_soundbank((d / (name + ".chbank")).string()).mode_count(), 4u);
    }
    EXPECT_GE(used.size(), 2u) << "one rank ran everything:\n" << out;
  }
}
#endif

// The shipped manifests stay valid: a dry run reads them, checks every asset's options and
// plans, writing nothing.
TEST(BatchCli, ShippedManifestsAreValid) {
  for (const char* m : {"/examples/batch/bundled.json", "/bench/batch_bundled.json"}) {
    const chladni::test::CliResult r =
        run_cli("batch " + std::string(CHLADNI_SOURCE_DIR) + m + " --dry-run -o " +
                chladni::test::temp_path("chladni_batch_dry_" + std::to_string(::getpid())));
    EXPECT_EQ(r.code, 0) << m << "\n" << r.output;
    EXPECT_NE(r.output.find("teapot_solid_selfintersecting  pending"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("spot "), std::string::npos) << r.output;
    EXPECT_FALSE(
        fs::exists(chladni::test::temp_path("chladni_batch_dry_" + std::to_string(::getpid()))));
  }
}
