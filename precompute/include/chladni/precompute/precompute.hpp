#pragma once
// The whole pipeline for one asset: mesh file -> checked (and repaired) surface -> tetrahedra ->
// K, M -> eigenmodes -> damping and band limits -> soundbank.
#include <array>
#include <string>
#include <vector>

#include "chladni/core/soundbank.hpp"
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
