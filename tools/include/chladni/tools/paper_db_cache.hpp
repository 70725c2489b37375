#pragma once
// The default paper sound database, generated once and then read from a cache: generating it
// takes about 1.7 s, which dominated `chladni paper` on short animations. The cache is a binary
// snapshot (every float exact, so a cached run sounds the same as a generated one) guarded by a
// CRC-32; a snapshot that does not read back is generated anew and replaced.
#include <filesystem>
#include <string>

#include "chladni/runtime/paper/paper_database.hpp"

namespace chladni::tools {

/// $CHLADNI_CACHE_DIR, else $XDG_CACHE_HOME/chladni, else $HOME/.cache/chladni; empty when
/// CHLADNI_CACHE_DIR is set to "" or none is known (then nothing is cached).
std::filesystem::path cache_dir();

/// The snapshot's file in `dir`: the name carries the generator's version.
std::filesystem::path paper_db_snapshot_path(const std::filesystem::path& dir);

/// Writes `db` to `path` atomically (InputError naming it on failure).
void write_paper_db_snapshot(const std::filesystem::path& path, const runtime::PaperSoundDb& db);
/// Reads a snapshot; InputError naming the file and what is wrong (bad magic, version, CRC,
/// truncation, values the database's validate() refuses).
runtime::PaperSoundDb read_paper_db_snapshot(const std::filesystem::path& path);

/// The default database (generate_paper_database({})): from the snapshot in `dir` when it reads
/// back, else generated and, when `dir` is not empty, cached there. `note` receives one line for
/// the user saying which happened, where, and how long it took.
runtime::PaperSoundDb default_paper_database(const std::filesystem::path& dir, std::string& note);

}  // namespace chladni::tools
