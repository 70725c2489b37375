// Batch manifests (JSON, CSV) and their errors, and the job files the batch hands its children.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "batch_fixtures.hpp"
#include "chladni/core/error.hpp"
#include "chladni/precompute/batch.hpp"
#include "cli_support.hpp"

using namespace chladni::test::batch_fixtures;
using chladni::test::run_cli;

namespace {

std::string manifest_error(const fs::path& path) {
  try {
    batch::read_manifest(path.string(), "", fake_schema());
  } catch (const chladni::InputError& e) {
    return e.what();
  }
  return "(no error)";
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
