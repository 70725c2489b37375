#pragma once
// How many modes a solid holds below a frequency, before any mesh is made: sizes the memory
// check of a band search and tells the user how large the band is.
#include "chladni/core/material.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

/// Modes (rigid ones excluded) of the solid bounded by `surface` in `material` below
/// `max_frequency` Hz, from its volume, area and local thickness; `checked` is check_mesh's
/// report on `surface` (its volume and bounding box).
double band_modes(const SurfaceMesh& surface, const MeshReport& checked, const Material& material,
                  double max_frequency);

}  // namespace chladni::precompute
