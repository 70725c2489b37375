#pragma once
// A closed triangle surface as read from a file, and its checks (CGAL Polygon Mesh Processing);
// its repair is mesh_repair.hpp.
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "chladni/core/modal_model.hpp"

namespace chladni::precompute {

struct SurfaceMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
};

/// Length unit of a mesh file's coordinates.
double unit_scale(const std::string& unit);  ///< "m", "cm", "mm" -> 1, 0.01, 0.001

/// Reads OBJ, OFF, PLY or STL (by extension, case-insensitive) and multiplies the coordinates by
/// `scale`. Polygons with more than three corners are fan-triangulated. Throws InputError naming
/// the file when it cannot be read, has no triangles, refers to missing vertices or holds
/// non-finite coordinates.
SurfaceMesh read_mesh(const std::string& path, double scale = 1.0);

/// Writes an OBJ (for repaired meshes and tests).
void write_obj(const std::string& path, const SurfaceMesh& mesh);

/// What check_mesh found. Examples hold up to five offending items each.
struct MeshReport {
  std::size_t vertices = 0, triangles = 0;
  std::size_t nonfinite_vertices = 0;
  std::size_t degenerate_faces = 0;
  std::vector<std::size_t> degenerate_examples;
  std::size_t boundary_edges = 0;
  std::vector<std::pair<uint32_t, uint32_t>> boundary_examples;
  std::size_t non_manifold_edges = 0;
  std::vector<std::pair<uint32_t, uint32_t>> non_manifold_edge_examples;
  std::size_t inconsistent_edges = 0;  ///< edges used twice in the same direction
  std::vector<std::pair<uint32_t, uint32_t>> inconsistent_examples;
  std::size_t non_manifold_vertices = 0;
  std::vector<uint32_t> non_manifold_vertex_examples;
  std::size_t components = 0;  ///< connected pieces, cavities included
  /// Of those, when the surface is closed and they could be compared: outer pieces (one for a
  /// solid), cavities (pieces inside one, wound into themselves), pieces inside the material but
  /// wound outward, and loose pieces lying in a cavity. Each example names a face of the piece.
  std::size_t outer_pieces = 0, cavities = 0, outward_inner_pieces = 0, loose_pieces = 0;
  std::vector<std::size_t> outward_inner_examples, loose_examples;
  bool self_intersections_checked = false;
  std::size_t self_intersections = 0;  ///< intersecting face pairs
  std::vector<std::pair<std::size_t, std::size_t>> self_intersection_examples;
  double volume = 0;  ///< signed, m^3; > 0 when outward oriented
  std::array<double, 3> bbox_min{}, bbox_max{};

  /// The signed volume is negligible against the bounding box: a flat or open sheet.
  bool encloses_no_volume() const;
  /// One line per problem, each naming counts and example faces, edges or vertices (0-based).
  std::vector<std::string> problems() const;
  bool ok() const { return problems().empty(); }
};

/// Closed, 2-manifold, consistently and outward oriented, no degenerate faces, no
/// self-intersections, positive volume, finite coordinates, one outer piece, with any cavities
/// inside it wound so that their faces point into the cavity (a hollow body).
MeshReport check_mesh(const SurfaceMesh& mesh);

/// Throws InputError("<origin>: mesh is not a valid solid: ...") listing every problem.
void require_valid(const MeshReport& report, const std::string& origin, bool after_repair);

}  // namespace chladni::precompute
