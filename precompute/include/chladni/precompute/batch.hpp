#pragma once
// The batch driver: a manifest of assets, each precomputed by its own process (a crash takes
// down one asset, not the batch), largest first, several at once with the memory budget shared,
// skipping assets whose soundbank is current. docs/batch.md. The options a manifest states are
// the precompute command's, which the command's own parser checks (OptionSchema); a child gets
// its job as a file of this library's format (ChildJob), so the driver names none of them.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace chladni::precompute::batch {

/// One asset of a manifest, resolved.
struct Asset {
  std::string name;               ///< unique within the manifest: names its log and summary row
  std::string mesh, output;       ///< paths as given, relative ones resolved against the manifest
  std::vector<std::string> args;  ///< precompute options, e.g. {"--material", "brass"}
  std::string where;              ///< "MANIFEST: assets[3]" or "MANIFEST:7", for messages
  std::uint64_t cost = 0;         ///< scheduling weight: the mesh file's size in bytes
  bool own_memory = false;        ///< its options set the eigen-solve's memory limit themselves
  bool own_threads = false;       ///< its options set the thread count themselves
};

struct Manifest {
  std::string path;
  std::string output_dir;
  std::vector<Asset> assets;
};

/// What the precompute command accepts, from its own option parser.
struct OptionSchema {
  /// Managed: the batch sets it for every asset (its output, summary, stamp), so a manifest may
  /// not.
  enum Kind { Unknown, Flag, Value, Managed };
  /// The kind of option `name` (long name without dashes, e.g. "max-modes").
  std::function<Kind(const std::string& name)> kind;
  /// Which of the batch's shares an asset's options set themselves.
  struct Own {
    bool memory = false, threads = false;
  };
  /// Checks one asset's options as precompute would parse them for `mesh` and `output`; throws
  /// InputError with the parser's message.
  std::function<Own(const std::string& mesh, const std::string& output,
                    const std::vector<std::string>& options)>
      check;
};

/// One asset's run as the batch hands it to a child process: a JSON file of this library's own
/// keys, read back by whatever runs the job (`chladni batch-job FILE`).
struct ChildJob {
  std::string mesh, output;
  std::vector<std::string> options;  ///< the asset's, as its manifest states them
  double memory_bytes = -1;          ///< the eigen-solve's share of the budget; < 0: its own
  int threads = 0;                   ///< threads for the asset; 0: its own
  std::string summary;               ///< where the run writes its JSON summary
  std::string stamp;                 ///< recorded in the soundbank's META ("batch_stamp")
};
/// Writes `job` to `path` atomically (InternalError on failure).
void write_child_job(const std::string& path, const ChildJob& job);
/// InputError naming `path` and the JSON path of what is wrong.
ChildJob read_child_job(const std::string& path);

/// Reads a JSON or CSV manifest (by extension: .csv is CSV, anything else JSON). Every problem
/// throws InputError naming the manifest and the JSON path or CSV line. A non-empty
/// `output_dir` replaces the manifest's.
Manifest read_manifest(const std::string& path, const std::string& output_dir,
                       const OptionSchema& schema);

/// Hash (XXH3-128, hex) of what decides an asset's soundbank: the tool version, the mesh file's
/// bytes and the options. Precompute records it in the soundbank's META as "batch_stamp".
std::string input_stamp(const Asset& asset);
/// The stamp recorded by a valid soundbank at `path`; empty when it is missing, unreadable,
/// corrupted or carries none.
std::string recorded_stamp(const std::string& path);

/// Pending: a dry run's asset that would run.
enum class Status { Ok, Current, Pending, BadInput, OverBudget, Failed, Crashed };
const char* status_name(Status s);
/// A multi-line error message (a mesh report lists its problems) on one line.
std::string one_line(const std::string& text);

struct Result {
  std::string name;
  Status status = Status::Failed;
  std::size_t modes = 0;
  double seconds = 0;
  double peak_mb = 0;  ///< the precompute process's peak resident memory
  int rank = 0;        ///< MPI rank that ran it (0 without MPI)
  std::string error;   ///< the asset's error message, or what killed it
  std::string log;     ///< its precompute log
};

struct RunOptions {
  /// The program and its first arguments that run one job: the job file's path is appended
  /// (e.g. {"/usr/bin/chladni", "batch-job"}).
  std::vector<std::string> command;
  int jobs = 1;               ///< assets at once (per MPI rank)
  int threads = 0;            ///< per asset; 0: the cores divided among the jobs
  double memory_budget = -1;  ///< bytes for all jobs of this machine; < 0: 80 % of available
  bool force = false;         ///< recompute current assets too
  bool dry_run = false;       ///< plan and report, run nothing
  std::string log_dir;        ///< per-asset logs and JSON summaries; empty: OUTPUT_DIR/batch-logs
  std::function<void(const std::string&)> print;  ///< progress lines
};

struct Summary {
  std::vector<Result> results;  ///< in manifest order
  double seconds = 0;
  int ranks = 1;
  int root_exit = -1;  ///< on MPI ranks other than 0: the exit code rank 0 decided
  /// 0 when every asset succeeded or was current, 1 when one failed for another reason than
  /// its input (a crash, an internal error), else 2 when one had bad input or no memory.
  int exit_code() const;
};

/// Runs the batch on this machine.
Summary run_batch(const Manifest& manifest, const RunOptions& options);

/// True when this process was started by mpirun/srun (the MPI environment variables are set).
bool launched_by_mpi();
/// Runs the batch across the MPI job's ranks (rank 0 hands out assets and gathers results).
/// Throws InputError when this build has no MPI. `manifest_error` is this rank's manifest
/// error (empty when it read the manifest): the ranks agree before any work starts.
Summary run_batch_mpi(const Manifest& manifest, const std::string& manifest_error,
                      const RunOptions& options, bool& is_root);

/// The summary table, one row per asset.
std::string summary_table(const Summary& summary);
/// The summary as JSON text.
std::string summary_json(const Manifest& manifest, const Summary& summary);

}  // namespace chladni::precompute::batch
