#include "runner.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/precompute/eigensolve.hpp"

namespace chladni::precompute::batch {

namespace fs = std::filesystem;

namespace {

std::string duration_text(double s) {
  char buf[32];
  if (s < 90)
    std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 5400)
    std::snprintf(buf, sizeof buf, "%.0f min", s / 60);
  else
    std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  return buf;
}

}  // namespace

std::string log_folder(const Manifest& m, const RunOptions& o) {
  return o.log_dir.empty() ? (fs::path(m.output_dir) / "batch-logs").string() : o.log_dir;
}

Plan make_plan(const Manifest& m, const RunOptions& o, std::vector<Result>& results) {
  Plan p;
  if (!o.dry_run) {
    for (const std::string& dir : {m.output_dir, log_folder(m, o)}) {
      std::error_code ec;
      fs::create_directories(dir, ec);
      if (!fs::is_directory(dir, ec))
        throw InputError("batch: cannot create folder " + dir + (ec ? ": " + ec.message() : ""));
    }
  }
  results.assign(m.assets.size(), Result{});
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < m.assets.size(); ++i) {
    const Asset& a = m.assets[i];
    results[i].name = a.name;
    p.stamps.push_back(input_stamp(a));
    if (!o.dry_run) {
      std::error_code ec;
      fs::create_directories(fs::path(a.output).parent_path(), ec);
      remove_stale_temporaries(a.output);
    }
    if (!o.force && !p.stamps.back().empty() && recorded_stamp(a.output) == p.stamps.back()) {
      results[i].status = Status::Current;
      continue;
    }
    results[i].status = Status::Pending;
    todo.push_back(i);
  }
  std::stable_sort(todo.begin(), todo.end(), [&](std::size_t x, std::size_t y) {
    return m.assets[x].cost > m.assets[y].cost;
  });
  p.queue.assign(todo.begin(), todo.end());
  return p;
}

Runner::Runner(const Manifest& m, const RunOptions& o, const Plan& plan, int share)
    : m_(m), o_(o), plan_(plan), log_dir_(log_folder(m, o)), ran_alone_(m.assets.size(), false) {
  share = std::max(1, share);
  budget_ = (o.memory_budget < 0 ? default_memory_budget() : o.memory_budget) / share;
  cores_ = std::max(1, int(std::thread::hardware_concurrency()) / share);
}

bool Runner::can_start() const {
  if (int(children_.size()) >= std::max(1, o_.jobs)) return false;
  return std::none_of(children_.begin(), children_.end(), [](const Child& c) { return c.alone; });
}

void Runner::start(std::size_t asset, bool alone) {
  const int jobs = alone ? 1 : std::max(1, o_.jobs);
  const int threads = o_.threads > 0 ? o_.threads : std::max(1, cores_ / jobs);
  // Budget 0 means no limit; the children then get none either (0 GB = unlimited).
  const double memory = budget_ > 0 ? std::max(budget_ / jobs, 1e6) : 0;
  children_.push_back(
      start_child(o_, log_dir_, m_.assets[asset], asset, plan_.stamps[asset], memory, threads));
  children_.back().alone = alone;
  if (alone) ran_alone_[asset] = true;
}

std::vector<std::pair<std::size_t, Result>> Runner::reap(bool block) {
  std::vector<std::pair<std::size_t, Result>> out;
  pid_t pid = 0;
  int status = 0;
  double peak = 0;
  while (!children_.empty() && wait_any(block && out.empty(), pid, status, peak)) {
    const auto it = std::find_if(children_.begin(), children_.end(),
                                 [&](const Child& c) { return c.pid == pid; });
    if (it == children_.end()) continue;  // not ours
    out.emplace_back(it->asset, child_result(m_.assets[it->asset], *it, status, peak));
    children_.erase(it);
  }
  return out;
}

bool Runner::requeue_alone(std::size_t asset, const Result& r,
                           std::deque<std::size_t>& alone) const {
  if (r.status != Status::OverBudget || std::max(1, o_.jobs) <= 1 || m_.assets[asset].own_memory ||
      ran_alone_[asset])
    return false;
  if (o_.print) o_.print("over budget " + r.name + ": will retry alone at the end");
  alone.push_back(asset);
  return true;
}

Reporter::Reporter(const Manifest& m, const RunOptions& o, const Plan& plan)
    : m_(m), o_(o), total_(plan.queue.size()), start_(std::chrono::steady_clock::now()) {
  for (std::size_t i : plan.queue) cost_left_ += double(m.assets[i].cost) + 1;
}

void Reporter::started(std::size_t asset, bool alone, int rank) const {
  if (!o_.print) return;
  std::string line = "start " + m_.assets[asset].name;
  if (rank > 0) line += " on rank " + std::to_string(rank);
  if (alone) line += " alone, with the whole memory budget";
  o_.print(line);
}

void Reporter::finished(std::size_t asset, const Result& r) {
  ++done_;
  const double c = double(m_.assets[asset].cost) + 1;
  cost_done_ += c;
  cost_left_ = std::max(0.0, cost_left_ - c);
  if (!o_.print) return;
  char head[64];
  std::snprintf(head, sizeof head, "[%zu/%zu] ", done_, total_);
  std::string line = head + std::string(status_name(r.status)) + " " + r.name;
  char buf[160];
  if (r.status == Status::Ok)
    std::snprintf(buf, sizeof buf, ": %zu modes, %.1f s, %.0f MB", r.modes, r.seconds, r.peak_mb);
  else
    std::snprintf(buf, sizeof buf, " after %.1f s: ", r.seconds);
  line += buf;
  if (r.status != Status::Ok) line += one_line(r.error);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (done_ < total_ && cost_done_ > 0)
    line += "  (ETA " + duration_text(elapsed * cost_left_ / cost_done_) + ")";
  o_.print(line);
}

}  // namespace chladni::precompute::batch
