#pragma once
// The repair ladder: a surface that is not a valid solid is fixed by the mildest rung that
// works, and how far the fix moved it is measured and reported (docs/repair.md).
//   1. local fixes (CGAL Polygon Mesh Processing): merge duplicate vertices, orient, stitch,
//      drop degenerate faces, fill small holes, remesh needle triangles;
//   2. CGAL's self-intersection removal, where it leaves a valid solid;
//   3. CGAL's 3D Alpha Wrapping (Portaneri et al., "Alpha Wrapping with an Offset", SIGGRAPH
//      2022): a watertight, 2-manifold, intersection-free surface at `offset` outside the input,
//      whose ball of radius `alpha` closes gaps and holes narrower than about alpha.
#include <cstddef>
#include <string>
#include <vector>

#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

struct RepairOptions {
  std::size_t max_hole_edges = 200;  ///< rung 1 fills border cycles up to this many edges
  double min_angle_deg = 5;          ///< remesh the surface when a triangle angle is smaller
  /// Rung 3's parameters (m); 0: derived from the object (wrap_defaults).
  double wrap_alpha = 0, wrap_offset = 0;
  /// A repair whose symmetric Hausdorff distance exceeds this fraction of the bounding-box
  /// diagonal, or which changes the volume by more than this fraction, is refused.
  double max_distance = 0.10, max_volume_change = 0.10;
  /// Disjoint parts below this fraction of the largest one's volume are dropped as debris.
  double debris_volume = 1e-3;
};

/// Which rung produced the surface that was kept.
enum class RepairRung { None, Local, SelfIntersections, Wrap };
const char* to_string(RepairRung rung);

struct RepairReport {
  RepairRung rung = RepairRung::None;
  std::vector<std::string> log;  ///< one line per change made
  /// Non-empty when the input cannot be made a solid, or its repair would move it too far: the
  /// reason, with its numbers (the mesh is then left as the last rung made it).
  std::string refusal;
  double size = 0;  ///< bounding-box diagonal of the input, m
  /// Distances (m), sampled on both surfaces: from the input to the repaired surface, from the
  /// repaired surface to the input, and the larger of the two (symmetric Hausdorff).
  double to_repaired = 0, to_input = 0, hausdorff = 0;
  /// Enclosed volumes (m^3). The input's is its signed volume about its centroid, exact when it
  /// is closed (`input_closed`), an estimate across its holes otherwise.
  double volume_input = 0, volume_repaired = 0;
  bool input_closed = true;
  double alpha = 0, offset = 0;  ///< the wrap's, when rung 3 ran (m)
  double thinnest = 0;           ///< the thinnest wall the defaults were derived from (m)
  double volume_change() const;  ///< (repaired - input) / |input|; 0 when input has none
  bool changed() const { return rung != RepairRung::None; }
};

/// Runs the ladder on `mesh`. On success the mesh is a valid solid (check_mesh(mesh).ok()) and
/// the report says which rung made it and how far it moved; otherwise report.refusal says why.
RepairReport repair_mesh(SurfaceMesh& mesh, const RepairOptions& options = {});

}  // namespace chladni::precompute
