#include "child.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chladni/core/error.hpp"

extern char** environ;

namespace chladni::precompute::batch {

namespace {

// What the precompute said before exiting: its log from the last "error: " line on.
std::string error_line(const std::string& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line)) {
    if (line.rfind("error: ", 0) == 0)
      last = line.substr(7);
    else if (!last.empty())
      last += "\n" + line;
  }
  return last;
}

}  // namespace

Child start_child(const RunOptions& o, const std::string& log_dir, const Asset& a,
                  std::size_t index, const std::string& stamp, double memory, int threads) {
  Child c;
  c.asset = index;
  c.log = log_dir + "/" + a.name + ".log";
  c.json = log_dir + "/" + a.name + ".json";
  ::unlink(c.json.c_str());  // a stale summary must not pass for this run's
  ChildJob job;
  job.mesh = a.mesh;
  job.output = a.output;
  job.options = a.args;
  job.memory_bytes = a.own_memory ? -1.0 : memory;
  job.threads = a.own_threads ? 0 : threads;
  job.summary = c.json;
  job.stamp = stamp;
  const std::string job_path = log_dir + "/" + a.name + ".job.json";
  write_child_job(job_path, job);
  if (o.command.empty()) throw InternalError("batch: no command to run a job with");
  std::vector<std::string> args = o.command;
  args.push_back(job_path);

  // Everything the child needs is built before fork: after it only async-signal-safe calls.
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_text;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "OPENBLAS_NUM_THREADS=", 21) != 0) env_text.emplace_back(*e);
  env_text.push_back("OPENBLAS_NUM_THREADS=" + std::to_string(threads));
  std::vector<char*> envp;
  for (std::string& s : env_text) envp.push_back(s.data());
  envp.push_back(nullptr);
  const int log_fd = ::open(c.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0)
    throw InternalError("batch: cannot write log " + c.log + ": " + std::strerror(errno));
  const int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the batch died before prctl took hold
    ::dup2(log_fd, 1);
    ::dup2(log_fd, 2);
    if (null_fd >= 0) ::dup2(null_fd, 0);
    ::execve(argv[0], argv.data(), envp.data());
    static const char msg[] = "error: batch: cannot start the precompute executable\n";
    (void)!::write(2, msg, sizeof msg - 1);
    ::_exit(127);
  }
  ::close(log_fd);
  if (null_fd >= 0) ::close(null_fd);
  if (pid < 0) throw InternalError(std::string("batch: fork failed: ") + std::strerror(errno));
  c.pid = pid;
  c.start = std::chrono::steady_clock::now();
  return c;
}

bool wait_any(bool block, pid_t& pid, int& status, double& peak_mb) {
  rusage ru{};
  for (;;) {
    pid = ::wait4(-1, &status, block ? 0 : WNOHANG, &ru);
    if (pid > 0) {
      peak_mb = double(ru.ru_maxrss) / 1024.0;  // KiB on Linux
      return true;
    }
    if (pid < 0 && errno == EINTR) continue;
    return false;
  }
}

Result child_result(const Asset& a, const Child& c, int status, double peak_mb) {
  Result r;
  r.name = a.name;
  r.log = c.log;
  r.peak_mb = peak_mb;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - c.start).count();
  if (WIFSIGNALED(status)) {
    r.status = Status::Crashed;
    r.error = std::string("killed by signal ") + std::to_string(WTERMSIG(status)) + " (" +
              ::strsignal(WTERMSIG(status)) + ")";
    return r;
  }
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 1;
  if (code == 0) {
    r.status = Status::Ok;
    try {
      std::ifstream in(c.json);
      const nlohmann::json j = nlohmann::json::parse(in);
      r.modes = j.at("modes").at("kept").get<std::size_t>();
      // The child resets its high-water mark per stage, which lowers what wait4 reports.
      r.peak_mb = std::max(r.peak_mb, j.value("peak_rss_mb", 0.0));
    } catch (const std::exception& e) {
      r.status = Status::Failed;
      r.error = "precompute succeeded but its summary " + c.json + " is unreadable: " + e.what();
    }
    return r;
  }
  r.status = code == 2                 ? Status::BadInput
             : code == kOverBudgetExit ? Status::OverBudget
                                       : Status::Failed;
  r.error = error_line(c.log);
  if (r.error.empty()) r.error = "precompute exited with code " + std::to_string(code);
  return r;
}

}  // namespace chladni::precompute::batch
