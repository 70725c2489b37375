// The batch driver: manifests (JSON, CSV) and their errors, bad assets skipped, reruns that skip
// what is current, a SIGKILL midway then a resume, memory shared and retried alone, MPI ranks.
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

#include "chladni/core/error.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/precompute/batch.hpp"
#include "cli_support.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
namespace batch = chladni::precompute::batch;
using chladni::test::run_cli;

namespace {

// A fresh folder per test and process.
fs::path fresh_dir(const std::string& name) {
  const fs::path d =
      chladni::test::temp_path("chladni_batch_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A closed box a x b x c metres (12 triangles); `open` leaves its top off.
void write_box(const fs::path& path, double a, double b, double c, bool open = false) {
  std::ofstream f(path);
  for (int v = 0; v < 8; ++v)
    f << "v " << a * (v & 1) << " " << b * (v >> 1 & 1) << " " << c * (v >> 2 & 1) << "\n";
  f << "f 1 3 4\nf 1 4 2\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\n"
       "f 2 8 6\n";
  if (!open) f << "f 5 6 8\nf 5 8 7\n";
}

batch::OptionSchema fake_schema() {
  batch::OptionSchema s;
  s.kind = [](const std::string& n) {
    if (n == "repair" || n == "no-transfer") return batch::OptionSchema::Flag;
    if (n == "material" || n == "max-modes" || n == "E" || n == "max-memory")
      return batch::OptionSchema::Value;
    return batch::OptionSchema::Unknown;
  };
  s.kind = [kind = s.kind](const std::string& n) {
    return n == "json" ? batch::OptionSchema::Managed : kind(n);
  };
  s.check = [](const std::string&, const std::string&, const std::vector<std::string>& args) {
    batch::OptionSchema::Own own;
    for (std::size_t i = 0; i + 1 < args.size(); ++i) {
      if (args[i] == "--max-modes" && args[i + 1] == "-1")
        throw chladni::InputError("--max-modes: negative");
      own.memory = own.memory || args[i] == "--max-memory";
    }
    return own;
  };
  return s;
}

std::string manifest_error(const fs::path& path) {
  try {
    batch::read_manifest(path.string(), "", fake_schema());
  } catch (const chladni::InputError& e) {
    return e.what();
  }
  return "(no error)";
}

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// Status per asset name from a batch summary.
std::map<std::string, std::string> statuses(const fs::path& summary) {
  std::map<std::string, std::string> out;
  const nlohmann::json s = read_json(summary);
  for (const auto& row : s["assets"])
    out[row["asset"].get<std::string>()] = row["status"].get<std::string>();
  return out;
}

}  // namespace

// Defaults merge under each asset's own options; options come out in one canonical order, so
// the same manifest always hashes alike; globs expand sorted; outputs land in output_dir.
TEST(BatchManifest, JsonDefaultsMergeIntoCanonicalArguments) {
  const fs::path d = fresh_dir("json");
  fs::create_directories(d / "m");
  write_box(d / "m/b.obj", 0.1, 0.1, 0.1);
  write_box(d / "m/a.obj", 0.1, 0.1, 0.1);
  write_box(d / "solo.obj", 0.1, 0.1, 0.1);
  std::ofstream(d / "list.json") << R"({
    "output_dir": "out",
    "defaults": {"material": "steel", "max_modes": 20, "--repair": true},
    "assets": [
      {"mesh": "solo.obj", "E": 2.5e11, "repair": false, "name": "one", "output": "x/one.chbank"},
      {"mesh": "m/*.obj", "max-modes": null}
    ]})";
  const batch::Manifest m = batch::read_manifest((d / "list.json").string(), "", fake_schema());
  ASSERT_EQ(m.assets.size(), 3u);
  EXPECT_EQ(m.output_dir, (d / "out").string());
  EXPECT_EQ(m.assets[0].name, "one");
  EXPECT_EQ(m.assets[0].output, (d / "out/x/one.chbank").string());
  EXPECT_EQ(m.assets[0].args, (std::vector<std::string>{"--E", "250000000000.0", "--material",
                                                        "steel", "--max-modes", "20"}));
  EXPECT_EQ(m.assets[1].name, "a");
  EXPECT_EQ(m.assets[2].name, "b");
  EXPECT_EQ(m.assets[1].output, (d / "out/a.chbank").string());
  EXPECT_EQ(m.assets[1].args, (std::vector<std::string>{"--material", "steel", "--repair"}));
  EXPECT_GT(m.assets[1].cost, 0u);
  // The stamp follows the mesh's bytes and the options, not the mesh's path.
  batch::Asset moved = m.assets[1];
  moved.mesh = (d / "m/b.obj").string();
  EXPECT_EQ(batch::input_stamp(moved), batch::input_stamp(m.assets[1]));
  moved.args.push_back("--no-transfer");
  EXPECT_NE(batch::input_stamp(moved), batch::input_stamp(m.assets[1]));
  EXPECT_EQ(batch::input_stamp(m.assets[1]).size(), 32u);
}

TEST(BatchManifest, CsvWithQuotesCommentsAndFlags) {
  const fs::path d = fresh_dir("csv");
  write_box(d / "a, b.obj", 0.1, 0.1, 0.1);
  write_box(d / "c.obj", 0.1, 0.1, 0.1);
  std::ofstream(d / "list.csv") << "# assets for level 3\n"
                                   "mesh, material, max_modes, repair\n"
                                   "\n"
                                   "\"a, b.obj\", brass, 10, yes\n"
                                   "c.obj,, , false\n";
  const batch::Manifest m = batch::read_manifest((d / "list.csv").string(), "", fake_schema());
  ASSERT_EQ(m.assets.size(), 2u);
  EXPECT_EQ(m.assets[0].mesh, (d / "a, b.obj").string());
  EXPECT_EQ(m.assets[0].args,
            (std::vector<std::string>{"--material", "brass", "--max-modes", "10", "--repair"}));
  EXPECT_TRUE(m.assets[1].args.empty());
  EXPECT_EQ(m.output_dir, d.string());
}

// What a spreadsheet saves as "CSV UTF-8": a byte-order mark, CRLF line ends, quoted cells.
TEST(BatchManifest, CsvFromASpreadsheet) {
  const fs::path d = fresh_dir("csv-excel");
  write_box(d / "a b.obj", 0.1, 0.1, 0.1);
  std::ofstream(d / "list.csv", std::ios::binary)
      << "\xEF\xBB\xBFmesh,material,name\r\n\"a b.obj\",brass,\"first\"\r\n";
  const batch::Manifest m = batch::read_manifest((d / "list.csv").string(), "", fake_schema());
  ASSERT_EQ(m.assets.size(), 1u);
  EXPECT_EQ(m.assets[0].mesh, (d / "a b.obj").string());
  EXPECT_EQ(m.assets[0].name, "first");
  EXPECT_EQ(m.assets[0].args, (std::vector<std::string>{"--material", "brass"}));
}

TEST(BatchManifest, ErrorsNameTheManifestAndWhere) {
  const fs::path d = fresh_dir("errors");
  write_box(d / "a.obj", 0.1, 0.1, 0.1);
  fs::create_directories(d / "other");
  write_box(d / "other/a.obj", 0.1, 0.1, 0.1);
  const auto check = [&](const std::string& file, const std::string& text,
                         const std::string& expect) {
    std::ofstream(d / file) << text;
    const std::string e = manifest_error(d / file);
    EXPECT_NE(e.find((d / file).string()), std::string::npos) << e;
    EXPECT_NE(e.find(expect), std::string::npos) << text << "\n -> " << e;
  };
  check("m.json", R"({"assets": [{"mesh": "a.obj", "maxmodes": 3}]})",
        "$.assets[0].maxmodes: unknown precompute option 'maxmodes'");
  check("m.json", R"({"assets": [{"mesh": "a.obj", "max-modes": -1}]})",
        "$.assets[0]: --max-modes: negative");
  check("m.json", R"({"assets": ["a.obj", "other/a.obj"]})",
        "$.assets[1]: asset name 'a' is also used by");
  check("m.json", R"({"assets": ["none/*.obj"]})", "$.assets[0]: '");
  check("m.json", R"({"assets": [{"mesh": "*.obj", "name": "x"}]})", "need a single mesh");
  check("m.json", R"({"defaults": {"json": "s.json"}, "assets": ["a.obj"]})",
        "$.defaults.json: --json is set by the batch");
  check("m.json", R"({"assets": [{"mesh": "a.obj", "repair": 1}]})",
        "$.assets[0].repair: a flag: expected true or false");
  check("m.json", R"({"assets": [{"mesh": "a.obj", "material": [1]}]})",
        "expected a number or a string");
  check("m.json", R"({"assets": [{"material": "steel"}]})", "missing required field 'mesh'");
  check("m.json", R"({"assets": ["a.obj"], "assets": []})", "duplicate key 'assets'");
  check("m.json", R"({"asset": []})", "unknown field 'asset'");
  check("m.json", R"({"assets": []})", "lists no assets");
  check("m.json", R"({"assets": [{"mesh": "a.obj", "name": "../x"}]})", "plain file name");
  check("m.csv", "material\nsteel\n", ":1: no 'mesh' column");
  check("m.csv", "mesh,material\na.obj\n", ":2: 1 fields, the header has 2");
  check("m.csv", "mesh,repair\na.obj,maybe\n", ":2: column 'repair': a flag");
  check("m.csv", "mesh\n\"a.obj\n", ":2: unterminated quote");
  check("m.csv", "mesh,name\na.obj,\"x\"y\n", ":2: 'y' after a closing quote");
}

// A child's job travels as a file of the batch library's own keys: it reads back as written, an
// asset's own memory limit keeps the batch's share out of it, and a bad job file is an input
// error naming the file and the field; `chladni batch-job` runs one.
TEST(BatchManifest, ChildJobsRoundTripAndBadOnesNameTheFileAndField) {
  const fs::path d = fresh_dir("job");
  write_box(d / "a.obj", 0.1, 0.1, 0.1);
  std::ofstream(d / "m.json") << R"({"assets": [{"mesh": "a.obj", "max-memory": 2}]})";
  std::ofstream(d / "m.csv") << "mesh,name\na.obj,x\n";
  const batch::Manifest m = batch::read_manifest((d / "m.json").string(), "", fake_schema());
  EXPECT_TRUE(m.assets[0].own_memory);
  EXPECT_FALSE(
      batch::read_manifest((d / "m.csv").string(), "", fake_schema()).assets[0].own_memory);

  batch::ChildJob job;
  job.mesh = (d / "a.obj").string();
  job.output = (d / "a.chbank").string();
  job.options = {"--max-modes", "4", "--no-transfer"};
  job.memory_bytes = 2.5e9;
  job.threads = 3;
  job.summary = (d / "a.json").string();
  job.stamp = std::string(32, 'f');
  batch::write_child_job((d / "a.job.json").string(), job);
  const batch::ChildJob back = batch::read_child_job((d / "a.job.json").string());
  EXPECT_EQ(back.mesh, job.mesh);
  EXPECT_EQ(back.output, job.output);
  EXPECT_EQ(back.options, job.options);
  EXPECT_EQ(back.memory_bytes, job.memory_bytes);
  EXPECT_EQ(back.threads, job.threads);
  EXPECT_EQ(back.summary, job.summary);
  EXPECT_EQ(back.stamp, job.stamp);

  const auto job_error = [&](const std::string& text) {
    std::ofstream(d / "bad.job.json") << text;
    try {
      batch::read_child_job((d / "bad.job.json").string());
    } catch (const chladni::InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string ok = nlohmann::json::parse(R"({"mesh": "a.obj", "output": "a.chbank",
    "options": [], "memory_bytes": -1, "threads": 0, "summary": "", "stamp": ""})")
                             .dump();
  EXPECT_EQ(job_error(ok), "(no error)");
  EXPECT_NE(job_error("[1]").find("bad.job.json: $: expected an object"), std::string::npos);
  std::string wrong = ok;
  wrong.replace(wrong.find("\"threads\":0"), 11, "\"threads\":\"2\"");
  EXPECT_NE(job_error(wrong).find("$.threads: wrong type (string)"), std::string::npos)
      << job_error(wrong);
  EXPECT_NE(job_error(R"({"mesh": "a.obj"})").find("missing field 'output'"), std::string::npos);

  // The job run by the command: the batch's threads and summary reach the precompute.
  const chladni::test::CliResult r = run_cli("batch-job " + (d / "a.job.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json summary = read_json(d / "a.json");
  EXPECT_EQ(summary["modes"]["kept"].get<int>(), 4);
  EXPECT_EQ(batch::recorded_stamp((d / "a.chbank").string()), job.stamp);
  const chladni::test::CliResult bad = run_cli("batch-job " + (d / "bad.job.json").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.output.find("bad.job.json"), std::string::npos) << bad.output;
}

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
