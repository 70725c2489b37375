// The batch on one machine, and its summary (table and JSON).
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "chladni/core/version.hpp"
#include "runner.hpp"

namespace chladni::precompute::batch {

std::string one_line(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\n') {
      out += text[i];
      continue;
    }
    std::size_t j = text.find_first_not_of(' ', i + 1);
    if (j == std::string::npos) break;
    if (text.compare(j, 2, "- ") == 0) j += 2;  // a mesh report's list of problems
    out += out.empty() || out.back() == ':' ? " " : "; ";
    i = j - 1;
  }
  return out;
}

const char* status_name(Status s) {
  switch (s) {
    case Status::Ok:
      return "ok";
    case Status::Current:
      return "current";
    case Status::Pending:
      return "pending";
    case Status::BadInput:
      return "bad input";
    case Status::OverBudget:
      return "over budget";
    case Status::Failed:
      return "failed";
    case Status::Crashed:
      return "crashed";
  }
  return "?";
}

int Summary::exit_code() const {
  if (root_exit >= 0) return root_exit;
  int code = 0;
  for (const Result& r : results) {
    if (r.status == Status::Failed || r.status == Status::Crashed) return 1;
    if (r.status == Status::BadInput || r.status == Status::OverBudget) code = 2;
  }
  return code;
}

Summary run_batch(const Manifest& m, const RunOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  Summary s;
  Plan plan = make_plan(m, o, s.results);
  if (!o.dry_run) {
    Runner runner(m, o, plan, 1);
    Reporter report(m, o, plan);
    std::deque<std::size_t> alone;
    while (!plan.queue.empty() || !alone.empty() || !runner.idle()) {
      while (runner.can_start() && !plan.queue.empty()) {
        report.started(plan.queue.front(), false, 0);
        runner.start(plan.queue.front(), false);
        plan.queue.pop_front();
      }
      if (runner.idle() && plan.queue.empty() && !alone.empty()) {
        report.started(alone.front(), true, 0);
        runner.start(alone.front(), true);
        alone.pop_front();
      }
      for (auto& [i, r] : runner.reap(true)) {
        if (runner.requeue_alone(i, r, alone)) continue;
        report.finished(i, r);
        s.results[i] = std::move(r);
      }
    }
  }
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

std::string summary_table(const Summary& s) {
  std::size_t w = 5;
  for (const Result& r : s.results) w = std::max(w, r.name.size());
  std::string out;
  char buf[512];
  std::snprintf(buf, sizeof buf, "%-*s  %-11s %6s %9s %9s  %s\n", int(w), "asset", "status",
                "modes", "time (s)", "peak MB", "error");
  out += buf;
  for (const Result& r : s.results) {
    const bool ran = r.status != Status::Current && r.status != Status::Pending;
    char modes[24] = "-", secs[24] = "-", peak[24] = "-";
    if (r.status == Status::Ok) std::snprintf(modes, sizeof modes, "%zu", r.modes);
    if (ran) std::snprintf(secs, sizeof secs, "%.1f", r.seconds);
    if (ran) std::snprintf(peak, sizeof peak, "%.0f", r.peak_mb);
    std::snprintf(buf, sizeof buf, "%-*s  %-11s %6s %9s %9s  ", int(w), r.name.c_str(),
                  status_name(r.status), modes, secs, peak);
    out += buf + one_line(r.error) + "\n";
  }
  std::size_t counts[7] = {};
  for (const Result& r : s.results) ++counts[int(r.status)];
  std::snprintf(buf, sizeof buf,
                "%zu assets: %zu ok, %zu current, %zu failed; %.1f s on %d rank%s\n",
                s.results.size(), counts[int(Status::Ok)], counts[int(Status::Current)],
                s.results.size() - counts[int(Status::Ok)] - counts[int(Status::Current)] -
                    counts[int(Status::Pending)],
                s.seconds, s.ranks, s.ranks == 1 ? "" : "s");
  out += buf;
  return out;
}

std::string summary_json(const Manifest& m, const Summary& s) {
  nlohmann::json j;
  j["generator"] = std::string("chladni ") + kVersion;
  j["manifest"] = m.path;
  j["output_dir"] = m.output_dir;
  j["seconds"] = s.seconds;
  j["ranks"] = s.ranks;
  j["exit_code"] = s.exit_code();
  nlohmann::json rows = nlohmann::json::array();
  for (std::size_t i = 0; i < s.results.size(); ++i) {
    const Result& r = s.results[i];
    nlohmann::json row = {{"asset", r.name},
                          {"mesh", m.assets[i].mesh},
                          {"output", m.assets[i].output},
                          {"status", status_name(r.status)}};
    if (r.status == Status::Ok) row["modes"] = r.modes;
    if (r.status != Status::Current && r.status != Status::Pending) {
      row["seconds"] = r.seconds;
      row["peak_memory_mb"] = r.peak_mb;
      row["rank"] = r.rank;
      row["log"] = r.log;
    }
    if (!r.error.empty()) row["error"] = r.error;
    rows.push_back(row);
  }
  j["assets"] = rows;
  return j.dump(2) + "\n";
}

}  // namespace chladni::precompute::batch
