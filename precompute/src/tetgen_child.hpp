#pragma once
#include <functional>
#include <optional>
#include <string>

#include "chladni/precompute/tet_mesh.hpp"

namespace chladni::precompute {

/// Runs `job` (a TetGen call) in a child process and reads its mesh back through a pipe.
/// Returns nothing, with `crash` saying how, when the child dies; rethrows the child's
/// exceptions as InputError.
std::optional<TetMesh> tetgen_isolated(const std::function<TetMesh()>& job, std::string& crash);

}  // namespace chladni::precompute
