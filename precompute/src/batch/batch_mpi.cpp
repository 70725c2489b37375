// The batch across MPI ranks: rank 0 plans, hands out assets largest first as ranks ask for
// them (each rank asks once per free slot), runs its own share, and gathers the results.
#include "chladni/core/error.hpp"
#include "runner.hpp"

#ifdef CHLADNI_HAVE_MPI
#include <mpi.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#endif

namespace chladni::precompute::batch {

#ifndef CHLADNI_HAVE_MPI

Summary run_batch_mpi(const Manifest&, const std::string&, const RunOptions&, bool& is_root) {
  is_root = true;
  throw InputError(
      "batch: started by mpirun, but this chladni was built without MPI (install "
      "libopenmpi-dev and reconfigure)");
}

#else

namespace {

constexpr int kTagRequest = 1, kTagAssign = 2;

// A request for work from a free slot, carrying the result of what that slot ran last.
std::string request_text(long asset, const Result* r) {
  nlohmann::json j = {{"asset", asset}};
  if (r)
    j["result"] = {{"status", int(r->status)},
                   {"modes", r->modes},
                   {"seconds", r->seconds},
                   {"peak_mb", r->peak_mb},
                   {"rank", r->rank},
                   {"error", r->error},
                   {"log", r->log},
                   {"name", r->name}};
  return j.dump();
}

int send_request(long asset, const Result* r) {
  const std::string text = request_text(asset, r);
  MPI_Send(text.data(), int(text.size()), MPI_CHAR, 0, kTagRequest, MPI_COMM_WORLD);
  int next = -1;
  MPI_Recv(&next, 1, MPI_INT, 0, kTagAssign, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return next;
}

int local_ranks() {
  const char* v = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE");
  if (!v) v = std::getenv("SLURM_NTASKS_PER_NODE");
  const int n = v ? std::atoi(v) : 1;
  return n > 0 ? n : 1;
}

void run_worker(const Manifest& m, const RunOptions& o, int rank) {
  Plan plan;
  plan.stamps.assign(m.assets.size(), std::string());
  Runner runner(m, o, plan, local_ranks());
  const int slots = std::max(1, o.jobs);
  int retired = 0;
  const auto take = [&](int next) {
    if (next < 0 || std::size_t(next) >= m.assets.size()) return void(++retired);
    plan.stamps[next] = input_stamp(m.assets[next]);
    runner.start(std::size_t(next), false);
  };
  for (int k = 0; k < slots; ++k) take(send_request(-1, nullptr));
  while (retired < slots) {
    for (auto& [i, r] : runner.reap(true)) {
      r.rank = rank;
      take(send_request(long(i), &r));
    }
  }
}

// Rank 0's side: answers requests as they come, runs its own slots, retries alone what did not
// fit a shared budget once every other slot has stopped.
void run_root(const Manifest& m, const RunOptions& o, int ranks, Summary& s) {
  Plan plan = make_plan(m, o, s.results);
  if (o.dry_run) plan.queue.clear();
  Runner runner(m, o, plan, local_ranks());
  Reporter report(m, o, plan);
  std::deque<std::size_t> alone;
  const int remote_slots = (ranks - 1) * std::max(1, o.jobs);
  int retired = 0;
  const auto record = [&](std::size_t i, Result r) {
    if (runner.requeue_alone(i, r, alone)) return;
    report.finished(i, r);
    s.results[i] = std::move(r);
  };
  for (;;) {
    bool progress = false;
    int flag = 0;
    MPI_Status st;
    while (MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &flag, &st), flag) {
      progress = true;
      int n = 0;
      MPI_Get_count(&st, MPI_CHAR, &n);
      std::string text(std::size_t(n), '\0');
      MPI_Recv(text.data(), n, MPI_CHAR, st.MPI_SOURCE, kTagRequest, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
      const nlohmann::json j = nlohmann::json::parse(text);
      const long done = j.at("asset").get<long>();
      if (done >= 0 && std::size_t(done) < m.assets.size() && j.contains("result")) {
        const nlohmann::json& jr = j["result"];
        Result r;
        r.name = jr.at("name").get<std::string>();
        r.status = Status(jr.at("status").get<int>());
        r.modes = jr.at("modes").get<std::size_t>();
        r.seconds = jr.at("seconds").get<double>();
        r.peak_mb = jr.at("peak_mb").get<double>();
        r.rank = jr.at("rank").get<int>();
        r.error = jr.at("error").get<std::string>();
        r.log = jr.at("log").get<std::string>();
        record(std::size_t(done), std::move(r));
      }
      int next = -1;
      if (!plan.queue.empty()) {
        next = int(plan.queue.front());
        plan.queue.pop_front();
        report.started(std::size_t(next), false, st.MPI_SOURCE);
      } else {
        ++retired;
      }
      MPI_Send(&next, 1, MPI_INT, st.MPI_SOURCE, kTagAssign, MPI_COMM_WORLD);
    }
    while (runner.can_start() && !plan.queue.empty()) {
      report.started(plan.queue.front(), false, 0);
      runner.start(plan.queue.front(), false);
      plan.queue.pop_front();
    }
    if (runner.idle() && plan.queue.empty() && retired == remote_slots && !alone.empty()) {
      report.started(alone.front(), true, 0);
      runner.start(alone.front(), true);
      alone.pop_front();
    }
    for (auto& [i, r] : runner.reap(false)) {
      progress = true;
      record(i, std::move(r));
    }
    if (plan.queue.empty() && alone.empty() && runner.idle() && retired == remote_slots) break;
    if (!progress) ::usleep(5000);
  }
}

}  // namespace

Summary run_batch_mpi(const Manifest& m, const std::string& manifest_error, const RunOptions& o,
                      bool& is_root) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) MPI_Init(nullptr, nullptr);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  is_root = rank == 0;
  // Every rank reads the manifest itself (a shared file system); all go on only if all could.
  int ok = manifest_error.empty() ? 1 : 0, all_ok = 0;
  MPI_Allreduce(&ok, &all_ok, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (!all_ok) {
    MPI_Finalize();
    if (!ok) throw InputError(manifest_error);
    throw InputError("batch: another MPI rank could not read the manifest (its message says why)");
  }
  const auto t0 = std::chrono::steady_clock::now();
  Summary s;
  s.ranks = ranks;
  int code = 0;
  try {
    if (is_root) {
      run_root(m, o, ranks, s);
      code = s.exit_code();
    } else {
      run_worker(m, o, rank);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: batch rank %d: %s\n", rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Bcast(&code, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!is_root) s.root_exit = code;
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  MPI_Finalize();
  return s;
}

#endif

}  // namespace chladni::precompute::batch
