#pragma once
// Shared by the fuzz harnesses: inputs go through the same file-reading entry points users hit,
// so each harness writes its bytes to a file in a private folder first. Only InputError (a
// clear message, exit 2) is an acceptable way to refuse an input; any other exception, crash or
// sanitizer report is a finding.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "chladni/core/error.hpp"

namespace chladni::fuzz {

/// A folder of this process's own (removed at exit), created on first use.
inline const std::filesystem::path& work_dir() {
  static const std::filesystem::path dir = [] {
    const char* base = std::getenv("TMPDIR");
    std::string tmpl = std::string(base && *base ? base : "/tmp") + "/chladni_fuzz_XXXXXX";
    if (!::mkdtemp(tmpl.data())) std::abort();
    static const std::string keep = tmpl;
    std::atexit([] { std::filesystem::remove_all(keep); });
    return std::filesystem::path(tmpl);
  }();
  return dir;
}

/// Writes `data` to `name` in work_dir() and returns its path.
inline std::string write_input(const std::string& name, const uint8_t* data, std::size_t size) {
  const std::filesystem::path p = work_dir() / name;
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  if (!f) std::abort();
  return p.string();
}

/// Runs `read`; InputError is the expected refusal, and its message must name `file`.
template <class F>
void expect_clean(const std::string& file, F&& read) {
  try {
    read();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    if (msg.find(file) == std::string::npos) {
      std::fprintf(stderr, "error message does not name %s: %s\n", file.c_str(), msg.c_str());
      std::abort();
    }
  }
}

}  // namespace chladni::fuzz
