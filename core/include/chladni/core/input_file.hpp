#pragma once
// Input files: read whole, with a size limit checked before allocating, so a directory, a
// device such as /dev/zero or a runaway pipe is refused with the file's name instead of hanging,
// growing without bound or failing deep inside a parser.
#include <cstdint>
#include <string>
#include <vector>

namespace chladni {

/// Documented limits (docs/robustness.md): JSON inputs (scenes, paper animations, database
/// indexes) and text tables are small; meshes, soundbanks and frame files may be large.
inline constexpr std::uint64_t kMaxTextInputBytes = std::uint64_t(256) << 20;
inline constexpr std::uint64_t kMaxBinaryInputBytes = std::uint64_t(8) << 30;

/// The bytes of `path`, a regular file or a pipe of at most `max_bytes`. Throws InputError
/// naming `what` and `path` when it is missing, a directory or a device, unreadable, or larger.
std::vector<std::uint8_t> read_input_file(const std::string& path, const std::string& what,
                                          std::uint64_t max_bytes);

}  // namespace chladni
