// TetGen in a child process: TetGen 1.5 aborts on failed internal assertions, which must end
// as an error to report, not as the end of the caller.
#include "tetgen_child.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <new>

#include "../peak_memory.hpp"
#include "chladni/core/error.hpp"

namespace chladni::precompute {
namespace {

void append(std::vector<char>& out, const void* p, std::size_t n) {
  const char* c = static_cast<const char*>(p);
  out.insert(out.end(), c, c + n);
}

void read_into(const std::vector<char>& in, std::size_t& at, void* p, std::size_t n) {
  if (in.size() - at < n) throw InternalError("TetGen's child process sent a short mesh");
  if (n == 0) return;  // an empty vector's data() may be null, which memcpy may not take
  std::memcpy(p, in.data() + at, n);
  at += n;
}

bool write_all(int fd, const char* p, std::size_t n) {
  while (n > 0) {
    const ssize_t w = write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w, n -= std::size_t(w);
  }
  return true;
}

// TetGen's quality refinement can run away on some surfaces (coupling.obj refined locally grew
// to 17 GB in 17 minutes): the child may take this much beyond what it shares with the parent.
// 8 GB meshes the 20 million tetrahedra tetrahedralize allows; CHLADNI_TETGEN_MEMORY_GB sets it.
double memory_allowance() {
  const char* gb = std::getenv("CHLADNI_TETGEN_MEMORY_GB");
  const double v = gb ? std::strtod(gb, nullptr) : 0;
  return v > 0 && std::isfinite(v) ? v * 1e9 : 8e9;
}

// Caps the child's address space at its size now plus the allowance.
void limit_memory(double allowance) {
  std::ifstream statm("/proc/self/statm");
  double pages = 0;
  if (!(statm >> pages)) return;
  const double limit = pages * double(sysconf(_SC_PAGE_SIZE)) + allowance;
  const rlimit r{rlim_t(limit), rlim_t(limit)};
  setrlimit(RLIMIT_AS, &r);
}

}  // namespace

std::optional<TetMesh> tetgen_isolated(const std::function<TetMesh()>& job, std::string& crash,
                                       double allowance, double cpu_seconds) {
  int fd[2];
  if (pipe(fd) != 0) return job();  // no isolation to be had: run in-process
  const pid_t pid = fork();
  if (pid < 0) {
    close(fd[0]), close(fd[1]);
    return job();
  }
  if (pid == 0) {
    close(fd[0]);
    // TetGen's failed assertions print its source line to stderr before the abort the parent
    // reports (and retries); the user sees the report, not the raw line, unless asked for.
    if (!std::getenv("CHLADNI_TETGEN_STDERR")) {
      const int null = open("/dev/null", O_WRONLY | O_CLOEXEC);
      if (null >= 0) dup2(null, STDERR_FILENO), close(null);
    }
    if (std::getenv("CHLADNI_TEST_TETGEN_ABORT")) std::abort();  // tests: TetGen's assertion
    const bool from_env = !(allowance > 0);  // else the caller's, from the mesh asked for
    if (from_env) allowance = memory_allowance();
    limit_memory(allowance);
    if (cpu_seconds > 0) {
      const rlimit cpu{rlim_t(std::ceil(cpu_seconds)), rlim_t(std::ceil(cpu_seconds)) + 1};
      setrlimit(RLIMIT_CPU, &cpu);
    }
    char over[96];
    std::snprintf(over, sizeof over, "its %.3g GB allowance%s", allowance / 1e9,
                  from_env ? " (CHLADNI_TETGEN_MEMORY_GB)" : "");
    std::string msg;
    std::vector<char> bytes;
    char status = 0;
    try {
      const TetMesh m = job();
      const uint64_t head[4] = {m.nodes.size(), m.tets.size(), m.surface_vertices,
                                m.surface_triangles.size()};
      append(bytes, head, sizeof head);
      append(bytes, m.nodes.data(), m.nodes.size() * sizeof(Vec3));
      append(bytes, m.tets.data(), m.tets.size() * sizeof(m.tets[0]));
      append(bytes, m.surface_triangles.data(),
             m.surface_triangles.size() * sizeof(m.surface_triangles[0]));
    } catch (const std::bad_alloc&) {
      status = 1;
      msg = std::string("TetGen needed more than ") + over;
      bytes.assign(msg.begin(), msg.end());
    } catch (const std::exception& e) {
      status = 1;
      msg = e.what();
      if (msg.find("out of memory") != std::string::npos) msg += std::string(" within ") + over;
      bytes.assign(msg.begin(), msg.end());
    }
    const bool ok = write_all(fd[1], &status, 1) && write_all(fd[1], bytes.data(), bytes.size());
    close(fd[1]);
    _exit(ok ? 0 : 1);
  }
  close(fd[1]);
  std::vector<char> bytes;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = read(fd[0], buf, sizeof buf);
    if (n > 0)
      bytes.insert(bytes.end(), buf, buf + n);
    else if (n == 0 || errno != EINTR)
      break;
  }
  close(fd[0]);
  int wstatus = 0;
  rusage usage{};
  while (wait4(pid, &wstatus, 0, &usage) < 0 && errno == EINTR) {
  }
  note_child_peak(usage);
  if (WIFSIGNALED(wstatus) || !WIFEXITED(wstatus) || WEXITSTATUS(wstatus) != 0 || bytes.empty()) {
    const int sig = WIFSIGNALED(wstatus) ? WTERMSIG(wstatus) : 0;
    crash = sig == SIGXCPU ? "it ran past its " + std::to_string(int(std::ceil(cpu_seconds))) +
                                 " s of CPU time"
            : sig ? std::string("an internal error, signal ") + std::to_string(sig)
                  : std::string("its process ended early");
    return std::nullopt;
  }
  if (bytes[0] == 1) throw InputError(std::string(bytes.begin() + 1, bytes.end()));
  std::size_t at = 1;
  uint64_t head[4];
  read_into(bytes, at, head, sizeof head);
  TetMesh m;
  m.nodes.resize(head[0]);
  m.tets.resize(head[1]);
  m.surface_vertices = head[2];
  m.surface_triangles.resize(head[3]);
  read_into(bytes, at, m.nodes.data(), m.nodes.size() * sizeof(Vec3));
  read_into(bytes, at, m.tets.data(), m.tets.size() * sizeof(m.tets[0]));
  read_into(bytes, at, m.surface_triangles.data(),
            m.surface_triangles.size() * sizeof(m.surface_triangles[0]));
  return m;
}

}  // namespace chladni::precompute
