#pragma once
// A surface denser than the modes need, coarsened before it is meshed: a scanned or sculpted
// asset of 100,000 triangles would otherwise set elements far finer than its first hundred modes
// ask for (a 94k-triangle copy of spot.obj: 214 s and 18 GB for 20 modes, against 10 s).
// Only simplify_surface.cpp includes CGAL's simplification.
#include <cstddef>
#include <functional>
#include <vector>

#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

/// Edge collapses in the order of Lindstrom & Turk's cost (1998: the volume and boundary change
/// a collapse causes), each placed where that cost is least, until `target_triangles` remain or
/// no collapse is allowed: a collapse is refused when a face it moves leaves the input surface's
/// `envelope` (a distance, m, tested at the face's corners, edge midpoints and centroid), turns
/// over, or gets a smallest angle under 15 degrees and below its own. The result may have more
/// triangles than `target_triangles`. `fraction` hears the share of the collapses done.
/// Throws InputError when CGAL cannot take the surface as a closed polygon mesh.
SurfaceMesh simplify_surface(const SurfaceMesh& surface, std::size_t target_triangles,
                             double envelope, const std::function<void(double)>& fraction = {});

/// The envelope within which a surface may move without moving a frequency by more than
/// `share` of `tolerance`: a plate's bending frequencies scale with its thickness, so a wall of
/// thickness t moved by d everywhere outward shifts them by at most about 2 d / t. From the
/// thinnest twentieth of the surface (by area) by local_thickness(); 0 when none is known.
double simplification_envelope(const SurfaceMesh& surface, double tolerance, double share = 0.2);

}  // namespace chladni::precompute
