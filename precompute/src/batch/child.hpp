#pragma once
// One asset's precompute as a child process: started with its share of threads and memory, its
// output going to a log, and turned into a Result when it ends.
#include <sys/types.h>

#include <chrono>
#include <string>

#include "chladni/precompute/batch.hpp"

namespace chladni::precompute::batch {

struct Child {
  pid_t pid = -1;
  std::size_t asset = 0;
  bool alone = false;  ///< runs with the whole memory budget, nothing beside it
  std::chrono::steady_clock::time_point start;
  std::string log, json;
};

/// Starts `chladni precompute` for `asset`, recording `stamp` in its soundbank, with `memory`
/// bytes for its eigen-solve (unless the manifest sets --max-memory) and `threads` threads. The
/// child is killed if this process dies. Throws InternalError when it cannot be started.
Child start_child(const RunOptions& options, const std::string& log_dir, const Asset& asset,
                  std::size_t index, const std::string& stamp, double memory, int threads);

/// Waits for one of this process's children (blocking, or not when `block` is false); returns
/// false when none has ended. `status` is the wait status, `peak_mb` its peak resident memory.
bool wait_any(bool block, pid_t& pid, int& status, double& peak_mb);

/// The Result of a child that ended with wait status `status`.
Result child_result(const Asset& asset, const Child& child, int status, double peak_mb);

/// Exit code precompute uses when the problem does not fit --max-memory.
inline constexpr int kOverBudgetExit = 3;

}  // namespace chladni::precompute::batch
