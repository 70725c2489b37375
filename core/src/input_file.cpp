#include "chladni/core/input_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "chladni/core/error.hpp"

namespace chladni {

namespace {

std::string mib(std::uint64_t bytes) {
  return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB";
}

}  // namespace

std::vector<std::uint8_t> read_input_file(const std::string& path, const std::string& what,
                                          std::uint64_t max_bytes) {
  if (path.empty()) throw InputError(what + ": the file name is empty");
  const std::string who = what + " " + path;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw InputError(who + ": cannot open (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw InputError(who + ": is a directory, not a file");
  if (!S_ISREG(st.st_mode) && !S_ISFIFO(st.st_mode))
    throw InputError(who + ": is a device or socket, not a file");
  if (S_ISREG(st.st_mode) && std::uint64_t(st.st_size) > max_bytes)
    throw InputError(who + ": " + mib(std::uint64_t(st.st_size)) + " is larger than the " +
                     mib(max_bytes) + " this kind of file may have");

  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw InputError(who + ": cannot open (" + std::strerror(errno) + ")");
  std::vector<std::uint8_t> bytes;
  if (S_ISREG(st.st_mode)) bytes.reserve(std::size_t(st.st_size));
  std::uint8_t chunk[1 << 16];
  for (;;) {
    const std::size_t got = std::fread(chunk, 1, sizeof chunk, f.get());
    if (bytes.size() + got > max_bytes)
      throw InputError(who + ": more than the " + mib(max_bytes) + " this kind of file may have");
    bytes.insert(bytes.end(), chunk, chunk + got);
    if (got < sizeof chunk) break;
  }
  if (std::ferror(f.get())) throw InputError(who + ": read failed");
  return bytes;
}

}  // namespace chladni
