#pragma once
// Output files: checked before the work that fills them, and replaced atomically, so a bad path
// fails at once and a failure midway never leaves a half-written file where a good one was.
#include <string>
#include <string_view>

namespace chladni {

/// Throws InputError naming `what` and `path` unless the file can be created or replaced: the
/// path is not empty, not a directory, and its folder exists and is one.
void check_output_path(const std::string& path, const std::string& what);

/// Writes `bytes` to a temporary file beside `path`, then renames it over `path`. Throws
/// InputError naming `what` on failure (the temporary is removed; `path` is untouched).
void write_file_atomic(const std::string& path, std::string_view bytes, const std::string& what);

/// The temporary name write_file_atomic and the other atomic writers use for `path`.
std::string temporary_path(const std::string& path);

/// Removes the temporaries (temporary_path's names, any PID) that killed writers left beside
/// `path`; errors are ignored.
void remove_stale_temporaries(const std::string& path);

/// Renames `tmp` over `path`, or removes `tmp` and throws InputError naming `what`.
void commit_temporary(const std::string& tmp, const std::string& path, const std::string& what);

}  // namespace chladni
