#pragma once
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

/// The surface with every edge at most `max_edge` long, its shape unchanged: long edges are
/// split at their midpoints, and within each plane the triangles are then made Delaunay by edge
/// flips, so the needles of a CAD box (a 0.4 m x 4 mm face as two triangles) become triangles
/// about as wide as they are long. A surface with no edge that long is returned as it is.
SurfaceMesh split_long_edges(SurfaceMesh surface, double max_edge);

}  // namespace chladni::precompute
