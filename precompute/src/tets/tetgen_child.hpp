#pragma once
#include <functional>
#include <optional>
#include <string>

#include "chladni/precompute/tet_mesh.hpp"

namespace chladni::precompute {

/// Runs `job` (a TetGen call) in a child process and reads its mesh back through a pipe.
/// Returns nothing, with `crash` saying how, when the child dies; rethrows the child's
/// exceptions as InputError. The child may allocate `allowance` bytes beyond what it shares
/// with the parent (0: CHLADNI_TETGEN_MEMORY_GB, or 8 GB); past that it fails with InputError.
/// With cpu_seconds > 0 a child still running after that much CPU time is stopped, as a crash.
std::optional<TetMesh> tetgen_isolated(const std::function<TetMesh()>& job, std::string& crash,
                                       double allowance = 0, double cpu_seconds = 0);

}  // namespace chladni::precompute
