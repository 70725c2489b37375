// The forked second solver (bem_side_process.hpp): records over a pipe, one per finished mode,
// then the child's times and an end mark (or its error).
#include "bem_side_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "../peak_memory.hpp"
#include "chladni/core/error.hpp"

namespace chladni::precompute::bem_detail {
namespace {

static_assert(std::is_trivially_copyable_v<ModeTransfer>);
static_assert(std::is_trivially_copyable_v<TransferTimes>);

enum Record : char { kMode = 'M', kTimes = 'T', kError = 'E', kEnd = 'D' };

bool write_all(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n, size -= std::size_t(n);
  }
  return true;
}

bool read_all(int fd, void* data, std::size_t size) {
  char* p = static_cast<char*>(data);
  while (size > 0) {
    const ssize_t n = ::read(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n, size -= std::size_t(n);
  }
  return true;
}

// The child: never returns, never runs the parent's destructors or atexit handlers.
[[noreturn]] void run_child(
    int fd, const std::function<void(const SideProcess::Emit&, TransferTimes&)>& work) {
  auto put = [&](const void* data, std::size_t size) {
    if (!write_all(fd, data, size)) ::_exit(1);  // the parent is gone
  };
  try {
    TransferTimes times;
    work(
        [&](std::size_t mode, const ModeTransfer& t, const std::vector<std::complex<double>>& a) {
          const char tag = kMode;
          const std::uint64_t index = mode, count = a.size();
          put(&tag, 1);
          put(&index, sizeof index);
          put(&t, sizeof t);
          put(&count, sizeof count);
          put(a.data(), a.size() * sizeof a[0]);
        },
        times);
    const char tag = kTimes;
    put(&tag, 1);
    put(&times, sizeof times);
  } catch (const std::exception& e) {
    const char tag = kError;
    const std::string what = e.what();
    const std::uint64_t size = what.size();
    put(&tag, 1);
    put(&size, sizeof size);
    put(what.data(), what.size());
  } catch (...) {
    ::_exit(1);
  }
  const char end = kEnd;
  put(&end, 1);
  ::close(fd);
  ::_exit(0);
}

}  // namespace

SideProcess::SideProcess(
    const std::function<void(const Emit&, TransferTimes&)>& work,
    std::function<void(std::size_t, const ModeTransfer&, std::vector<cd>&&)> receive)
    : receive_(std::move(receive)) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)  // not inherited by programs this process starts later
    throw InternalError(std::string("bem: cannot open a pipe: ") + std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]), ::close(fds[1]);
    throw InternalError(std::string("bem: cannot fork the second solver: ") + std::strerror(errno));
  }
  if (pid == 0) {
    ::close(fds[0]);
    run_child(fds[1], work);
  }
  ::close(fds[1]);
  pid_ = pid;
  fd_ = fds[0];
  reader_ = std::thread([this] { read_records(); });
}

void SideProcess::read_records() {
  for (;;) {
    char tag = 0;
    if (!read_all(fd_, &tag, 1)) return;  // finish() tells why from the exit status
    if (tag == kMode) {
      std::uint64_t index = 0, count = 0;
      ModeTransfer t;
      if (!read_all(fd_, &index, sizeof index) || !read_all(fd_, &t, sizeof t) ||
          !read_all(fd_, &count, sizeof count) || count > (1u << 20))
        return;
      std::vector<cd> a(count);
      if (!read_all(fd_, a.data(), count * sizeof(cd))) return;
      try {
        receive_(std::size_t(index), t, std::move(a));
      } catch (const std::exception& e) {
        if (error_.empty()) error_ = e.what();
      }
    } else if (tag == kTimes) {
      if (!read_all(fd_, &times_, sizeof times_)) return;
    } else if (tag == kError) {
      std::uint64_t size = 0;
      if (!read_all(fd_, &size, sizeof size) || size > (1u << 16)) return;
      std::string what(size, '\0');
      if (!read_all(fd_, what.data(), size)) return;
      error_ = what;
    } else if (tag == kEnd) {
      done_ = true;
      return;
    } else {
      return;
    }
  }
}

void SideProcess::finish(TransferTimes* times) {
  if (reader_.joinable()) reader_.join();
  int status = 0;
  pid_t got;
  rusage usage{};
  do got = ::wait4(pid_, &status, 0, &usage);
  while (got < 0 && errno == EINTR);
  if (got > 0) note_child_peak(usage);
  pid_ = -1;
  ::close(fd_);
  fd_ = -1;
  if (!error_.empty()) throw InternalError(error_);
  if (got < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0 || !done_) {
    const std::string how = got >= 0 && WIFSIGNALED(status)
                                ? "was killed by signal " + std::to_string(WTERMSIG(status)) +
                                      (WTERMSIG(status) == SIGKILL ? " (out of memory?)" : "")
                                : "stopped before its last mode";
    throw InternalError("bem: the second solver process " + how);
  }
  if (times)
    times->matrix += times_.matrix, times->solve += times_.solve, times->expand += times_.expand;
}

SideProcess::~SideProcess() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    if (reader_.joinable()) reader_.join();
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
  }
  if (reader_.joinable()) reader_.join();
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace chladni::precompute::bem_detail
