#pragma once
// The rungs of the repair ladder and the measures that judge them; repair_ladder.cpp composes
// them. Each CGAL family lives in one unit: local_repair.cpp (Polygon Mesh Processing),
// alpha_wrap.cpp (3D Alpha Wrapping), surface_measure.cpp (AABB trees).
#include <functional>
#include <string>
#include <vector>

#include "chladni/precompute/mesh_repair.hpp"

namespace chladni::precompute::repair {

using Say = std::function<void(const std::string&)>;

struct LocalFixes {
  SurfaceMesh surface;
  bool closed = false;           ///< no border left
  std::size_t holes_filled = 0;  ///< border cycles closed by new triangles
};

/// Rung 1: soup repair (duplicate vertices, degenerate and duplicate triangles), consistent
/// orientation, border stitching, degenerate faces, holes up to `max_hole_edges` filled.
LocalFixes local_fixes(const SurfaceMesh& input, std::size_t max_hole_edges, const Say& say);

/// Rung 2: CGAL's self-intersection removal, where any intersect. Returns how many face pairs
/// intersected before; `remaining` those left after.
std::size_t remove_self_intersections(SurfaceMesh& mesh, const Say& say, std::size_t& remaining);

/// Needle triangles (after hole filling or self-intersection removal) make sliver tetrahedra:
/// a closed surface is remeshed isotropically at its mean edge length when any angle is smaller.
void remesh_needles(SurfaceMesh& mesh, double min_angle_deg, const Say& say);

/// Each piece wound to bound the solid (outer faces out, cavities into themselves).
void orient_pieces(SurfaceMesh& mesh, const Say& say);

/// Rung 3: CGAL::alpha_wrap_3 of the triangle soup.
SurfaceMesh alpha_wrap(const SurfaceMesh& soup, double alpha, double offset);

/// Largest distance from points sampled on `from` (corners, and points inside triangles larger
/// than `spacing`) to the surface `to`: a one-sided Hausdorff distance, exact to about `spacing`.
/// With `skip_interior`, only points of `from` seen from outside it count: faces of overlapping
/// parts inside another part, or walls sealed in by filled holes, are not the solid's surface.
double one_sided_distance(const SurfaceMesh& from, const SurfaceMesh& to, double spacing,
                          bool skip_interior = false);

/// Smallest distance between two surfaces, from the vertices of each to the other; 0 when
/// their triangles intersect.
double gap_between(const SurfaceMesh& a, const SurfaceMesh& b);

/// Volume where the winding number of a closed (possibly self-intersecting, possibly
/// overlapping) surface is at least one: the union of the solids its pieces bound. Integrated
/// along a grid of parallel rays, counting signed crossings; `rays` per side.
double union_volume(const SurfaceMesh& surface, int rays = 160);

}  // namespace chladni::precompute::repair
