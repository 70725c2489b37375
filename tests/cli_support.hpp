#pragma once
// Running the chladni executable from tests: exit code and combined output.
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace chladni::test {

struct CliResult {
  int code;  ///< exit status; 128 + N when killed by signal N; 124 when it ran past the timeout
  std::string output;
};

/// Runs chladni with `args` (`env`: VAR=value assignments put first), killed after `timeout_s`.
inline CliResult run_cli(const std::string& args, const std::string& env = "",
                         int timeout_s = 600) {
  const std::string cmd = env + " timeout -k 5 " + std::to_string(timeout_s) + " " +
                          std::string(CHLADNI_EXE) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof(buf), p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), out};
}

}  // namespace chladni::test
