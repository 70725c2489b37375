#pragma once
// From a closed triangle mesh to a soundbank: the whole pipeline for one asset, mesh file ->
// checked (and repaired) surface -> tetrahedra -> K, M -> eigenmodes -> damping and band limits
// -> soundbank, refined until its estimate is within the tolerance. Entry points:
//   precompute_mesh, precompute_surface   the pipeline (below), with PrecomputeOptions
//   read_mesh, check_mesh, repair_mesh    the surface, its checks and the repair ladder
//                                         (precompute/surface_mesh.hpp, mesh_repair.hpp)
//   acoustic transfer                     per-mode radiation (precompute/acoustic_transfer.hpp)
// Many assets, one process each and across MPI ranks: chladni/precompute/batch.hpp (the
// chladni_batch library).
#include <array>
#include <string>
#include <vector>

#include "chladni/core/soundbank.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/precompute/mesh_repair.hpp"
#include "chladni/precompute/precompute_options.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

/// Runs the pipeline on `mesh_path`. Throws InputError for a bad mesh, material or option.
Soundbank precompute_mesh(const std::string& mesh_path, const PrecomputeOptions& options,
                          PrecomputeReport& report, const Progress& progress = {});

/// The same from a surface already in memory (in metres); `origin` names it in messages.
Soundbank precompute_surface(SurfaceMesh surface, const std::string& origin,
                             const PrecomputeOptions& options, PrecomputeReport& report,
                             const Progress& progress = {});

/// Outward unit vertex normals, area-weighted.
std::vector<std::array<float, 3>> vertex_normals(const SurfaceMesh& mesh);

}  // namespace chladni::precompute
