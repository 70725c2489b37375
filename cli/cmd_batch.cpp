// chladni batch MANIFEST: many assets precomputed, in parallel and resumable, on one machine or
// across MPI ranks (docs/batch.md). The driver is precompute/src/batch/.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <thread>

#include "chladni/core/error.hpp"
#include "chladni/core/material.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/precompute/batch.hpp"
#include "commands.hpp"

namespace chladni::cli {
namespace {

namespace fs = std::filesystem;
namespace batch = precompute::batch;

struct BatchArgs {
  std::string manifest, output_dir, summary, log_dir;
  int jobs = 0, threads = 0;
  double max_memory_gb = -1;
  bool force = false, dry_run = false, quiet = false;
};

// The precompute command line of one asset: its mesh and output, then its options.
std::vector<std::string> precompute_line(const std::string& mesh, const std::string& output,
                                         const std::vector<std::string>& options) {
  std::vector<std::string> args{"precompute", mesh, "-o", output};
  args.insert(args.end(), options.begin(), options.end());
  return args;
}

// Parses `args` (precompute_line) with a fresh parser, which runs the precompute if it was
// added to run; a parse error becomes an InputError prefixed by `where`.
void parse_precompute(CLI::App& app, const std::vector<std::string>& args,
                      const std::string& where = "") {
  std::vector<std::string> reversed{args.rbegin(), args.rend()};  // CLI11 pops from the back
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw InputError(where + e.what());
  }
}

// The batch sets these for every asset (docs/batch.md): a manifest may not.
bool managed(const std::string& name) {
  return name == "json" || name == "quiet" || name == "output" || name == "batch-stamp" ||
         name == "save-surface" || name == "help";
}

// The precompute command's own parser decides what a manifest may say.
batch::OptionSchema precompute_schema() {
  batch::OptionSchema s;
  auto app = std::make_shared<CLI::App>();  // asked about every option of every asset
  add_precompute(*app, false);
  s.kind = [app](const std::string& name) {
    const CLI::Option* opt = app->get_subcommand("precompute")->get_option_no_throw("--" + name);
    if (!opt) opt = app->get_subcommand("precompute")->get_option_no_throw("-" + name);
    if (opt && !opt->get_lnames().empty() && managed(opt->get_lnames().front()))
      return batch::OptionSchema::Managed;
    if (!opt || opt->get_group().empty()) return batch::OptionSchema::Unknown;
    return opt->get_items_expected_min() == 0 ? batch::OptionSchema::Flag
                                              : batch::OptionSchema::Value;
  };
  s.check = [](const std::string& mesh, const std::string& output,
               const std::vector<std::string>& options) {
    CLI::App app;  // a fresh parser per asset: parsing fills it
    add_precompute(app, false);
    CLI::App* cmd = app.get_subcommand("precompute");
    parse_precompute(app, precompute_line(mesh, output, options));
    // What only the run would find otherwise: the material preset and the damping model.
    if (const CLI::Option* m = cmd->get_option_no_throw("--material"); m && m->count())
      (void)find_material(m->as<std::string>());
    if (const CLI::Option* d = cmd->get_option_no_throw("--damping"); d && d->count())
      (void)DampingModel::parse(d->as<std::string>());
    return batch::OptionSchema::Own{cmd->get_option("--max-memory")->count() > 0,
                                    cmd->get_option("--threads")->count() > 0};
  };
  return s;
}

// One asset's job, as the batch wrote it: its precompute line, with the batch's share of memory
// and threads where the asset sets none, the summary and the stamp.
void run_batch_job(const std::string& path) {
  const batch::ChildJob job = batch::read_child_job(path);
  std::vector<std::string> args = precompute_line(job.mesh, job.output, job.options);
  if (job.memory_bytes >= 0) {
    char gb[32];
    std::snprintf(gb, sizeof gb, "%.9g", job.memory_bytes / 1e9);
    args.insert(args.end(), {"--max-memory", gb});
  }
  if (job.threads > 0) args.insert(args.end(), {"--threads", std::to_string(job.threads)});
  if (!job.summary.empty()) args.insert(args.end(), {"--json", job.summary});
  if (!job.stamp.empty()) args.insert(args.end(), {"--batch-stamp", job.stamp});
  CLI::App app;
  add_precompute(app, true);
  parse_precompute(app, args, path + ": ");  // what the run finds is its own error
}

std::string summary_path(const BatchArgs& a, const batch::Manifest& m) {
  return a.summary.empty() ? (fs::path(m.output_dir) / "batch-summary.json").string() : a.summary;
}

void run_batch_command(const BatchArgs& a) {
  batch::RunOptions o;
  o.command = {fs::read_symlink("/proc/self/exe").string(), "batch-job"};
  o.jobs = a.jobs > 0 ? a.jobs : std::max(1, int(std::thread::hardware_concurrency()));
  o.threads = a.threads;
  o.memory_budget = a.max_memory_gb < 0 ? -1.0 : a.max_memory_gb * 1e9;
  o.force = a.force;
  o.dry_run = a.dry_run;
  o.log_dir = a.log_dir;
  if (!a.quiet)
    o.print = [](const std::string& line) {
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    };
  batch::Manifest m;
  batch::Summary s;
  if (batch::launched_by_mpi()) {
    std::string error;
    try {
      m = batch::read_manifest(a.manifest, a.output_dir, precompute_schema());
    } catch (const InputError& e) {
      error = e.what();
    }
    bool root = true;
    s = batch::run_batch_mpi(m, error, o, root);
    // The other ranks exit 0: a non-zero exit makes mpirun abort the job, rank 0 too, which may
    // not have written the summary yet. mpirun's exit code is then rank 0's.
    if (!root) return;
  } else {
    m = batch::read_manifest(a.manifest, a.output_dir, precompute_schema());
    if (!a.dry_run) {
      std::error_code ec;
      if (a.summary.empty()) fs::create_directories(m.output_dir, ec);
      check_output_path(summary_path(a, m), "--summary");
    }
    s = batch::run_batch(m, o);
  }
  const std::string summary = summary_path(a, m);
  if (!a.quiet) std::printf("%s", batch::summary_table(s).c_str());
  if (!a.dry_run) {
    write_file_atomic(summary, batch::summary_json(m, s), "--summary");
    if (!a.quiet) std::printf("wrote %s\n", summary.c_str());
  }
  if (s.exit_code() != 0) throw ExitCode{s.exit_code()};
}

}  // namespace

void add_batch(CLI::App& app) {
  auto a = std::make_shared<BatchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "batch",
      "Precompute every asset of a manifest (JSON or CSV), in parallel and resumable; "
      "under mpirun across its ranks");
  cmd->add_option("manifest", a->manifest, "Manifest: .json, or .csv (docs/batch.md)")->required();
  cmd->add_option("-o,--output-dir", a->output_dir,
                  "Folder for the soundbanks (default: the manifest's output_dir, or its folder)");
  cmd->add_option("-j,--jobs", a->jobs, "Assets at once on this machine (0: one per core)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  cmd->add_option("--threads", a->threads, "Threads per asset (0: the cores divided among jobs)")
      ->check(thread_count())
      ->capture_default_str();
  cmd->add_option("--max-memory", a->max_memory_gb,
                  "Memory for all jobs together (GB; default 80 % of the memory available), "
                  "shared among them; an asset that does not fit its share is retried alone")
      ->check(finite_in(0, 1e6));
  cmd->add_flag("--force", a->force, "Recompute assets whose soundbank is current too");
  cmd->add_flag("--dry-run", a->dry_run, "Say what would run and what is current; run nothing");
  cmd->add_option("--summary", a->summary,
                  "Summary JSON to write (default OUTPUT_DIR/batch-summary.json)");
  cmd->add_option("--log-dir", a->log_dir, "Per-asset logs (default OUTPUT_DIR/batch-logs)");
  cmd->add_flag("-q,--quiet", a->quiet, "No progress and no table");
  cmd->callback([a] { run_batch_command(*a); });
  // What the batch starts for each asset: not for users, so not in the help.
  auto job = std::make_shared<std::string>();
  CLI::App* child = app.add_subcommand("batch-job", "Run one asset's job file of a batch");
  child->group("");
  child->add_option("job", *job, "Job file (JSON) the batch wrote")->required();
  child->callback([job] { run_batch_job(*job); });
}

}  // namespace chladni::cli
