#pragma once
// The connected pieces of a closed surface and how they nest: a hollow body is an outer piece
// with cavities inside it, each wound so that its faces point into the cavity.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "chladni/core/vec3.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

struct SurfacePieces {
  std::vector<uint32_t> of_triangle;  ///< piece index per triangle
  std::vector<std::size_t> first_triangle, triangles;
  std::vector<double> volume;  ///< signed, > 0 when the piece's faces point away from it
  /// How many other pieces enclose each one: 0 outer, 1 a cavity (or a piece inside the
  /// material), 2 a piece floating inside a cavity. Empty when nesting was not computed
  /// (too many pieces to compare at a reasonable cost).
  std::vector<int> depth;
  std::vector<int> parent;  ///< innermost enclosing piece, -1 for an outer one
  std::size_t count() const { return volume.size(); }
  bool nested() const { return !depth.empty(); }
  /// Inside an odd number of pieces and wound into itself: a hollow body's cavity.
  bool is_cavity(std::size_t p) const { return nested() && depth[p] % 2 == 1 && volume[p] < 0; }
};

/// Solid angle of triangle abc seen from p (Van Oosterom & Strackee 1983), signed by its
/// winding: 4 pi over a closed surface wound outward around p, 0 outside it.
double solid_angle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// Pieces joined through shared edges (pieces touching at a vertex only are separate), their
/// signed volumes and, when pieces × triangles stays small, their nesting by generalized winding
/// numbers (the surface must not intersect itself for the nesting to mean anything).
SurfacePieces surface_pieces(const SurfaceMesh& mesh);

/// A point strictly inside the cavity bounded by `piece` (a correctly wound cavity): halfway
/// along the ray from a large face's centroid, along its normal, to the next face it meets.
/// Throws InternalError when no ray finds the far side.
Vec3 point_in_cavity(const SurfaceMesh& mesh, const SurfacePieces& pieces, std::size_t piece);

/// Distance along the ray o + t dir (t > eps) to the nearest triangle not incident to vertex
/// `skip` (Moller & Trumbore 1997); +inf when none.
double ray_depth(const SurfaceMesh& mesh, const Vec3& o, const Vec3& dir, uint32_t skip,
                 double eps);

/// The triangles of the pieces `keep[p]` selects, with unused vertices dropped.
SurfaceMesh keep_pieces(const SurfaceMesh& mesh, const SurfacePieces& pieces,
                        const std::vector<bool>& keep);

/// The outer piece of a checked solid: what the air around it touches (cavities removed).
SurfaceMesh outer_surface(const SurfaceMesh& mesh);

}  // namespace chladni::precompute
