#pragma once
// The pieces every batch shares, local or across MPI ranks: which assets need running, the
// children running them on this machine, and the progress lines.
#include <chrono>
#include <deque>
#include <utility>
#include <vector>

#include "child.hpp"

namespace chladni::precompute::batch {

/// Assets to run, largest first; the results of those that are current are filled in.
struct Plan {
  std::deque<std::size_t> queue;
  std::vector<std::string> stamps;  ///< per asset
};
/// Creates the output and log folders (unless a dry run), removes temporaries that killed runs
/// left beside the outputs, and decides what is current.
Plan make_plan(const Manifest& m, const RunOptions& o, std::vector<Result>& results);

/// The log folder: RunOptions::log_dir or OUTPUT_DIR/batch-logs.
std::string log_folder(const Manifest& m, const RunOptions& o);

/// Children on this machine. `share` divides the machine's cores and memory (MPI ranks that
/// share a node).
class Runner {
 public:
  Runner(const Manifest& m, const RunOptions& o, const Plan& plan, int share);
  bool idle() const { return children_.empty(); }
  /// A slot is free and no asset runs alone.
  bool can_start() const;
  void start(std::size_t asset, bool alone);
  /// Results of children that ended; waits for one when `block` and some are running.
  std::vector<std::pair<std::size_t, Result>> reap(bool block);
  /// Queues `asset` on `alone` (and says so) when `r` is a refusal for memory that the whole
  /// budget, with nothing beside it, may cure: never for an asset that already ran alone.
  bool requeue_alone(std::size_t asset, const Result& r, std::deque<std::size_t>& alone) const;

 private:
  const Manifest& m_;
  const RunOptions& o_;
  const Plan& plan_;
  std::string log_dir_;
  double budget_ = 0;
  int cores_ = 1;
  std::vector<Child> children_;
  std::vector<bool> ran_alone_;  ///< per asset
};

/// Progress lines with an ETA from the mesh sizes done and left.
class Reporter {
 public:
  Reporter(const Manifest& m, const RunOptions& o, const Plan& plan);
  void started(std::size_t asset, bool alone, int rank) const;
  void finished(std::size_t asset, const Result& r);

 private:
  const Manifest& m_;
  const RunOptions& o_;
  std::size_t total_ = 0, done_ = 0;
  double cost_left_ = 0, cost_done_ = 0;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace chladni::precompute::batch
