#pragma once
// A SurfaceMesh as CGAL's polygon soup and mesh: the types and conversions the CGAL units
// (mesh_check.cpp, local_thickness.cpp, simplify_surface.cpp) share. Include it from those only.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_mesh_to_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <vector>

#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute::cgal_surface {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

inline std::vector<Point> to_points(const SurfaceMesh& m) {
  std::vector<Point> p;
  p.reserve(m.vertices.size());
  for (const Vec3& v : m.vertices) p.emplace_back(v[0], v[1], v[2]);
  return p;
}

inline std::vector<std::vector<std::size_t>> to_polygons(const SurfaceMesh& m) {
  std::vector<std::vector<std::size_t>> polys;
  polys.reserve(m.triangles.size());
  for (const auto& t : m.triangles) polys.push_back({t[0], t[1], t[2]});
  return polys;
}

/// `m` as a halfedge mesh whose faces are created in `m`'s order; false (and `mesh` left
/// unusable) when `m` is not a closed polygon mesh.
inline bool to_closed_mesh(const SurfaceMesh& m, Mesh& mesh) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  const auto polygons = to_polygons(m);
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) return false;
  PMP::polygon_soup_to_polygon_mesh(to_points(m), polygons, mesh);
  return mesh.number_of_faces() == m.triangles.size() && CGAL::is_closed(mesh);
}

/// Back to a SurfaceMesh (polygons fan-triangulated).
inline SurfaceMesh from_mesh(const Mesh& mesh) {
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polys;
  CGAL::Polygon_mesh_processing::polygon_mesh_to_polygon_soup(mesh, points, polys);
  SurfaceMesh out;
  for (const Point& p : points) out.vertices.push_back({p.x(), p.y(), p.z()});
  for (const auto& poly : polys)
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      out.triangles.push_back({uint32_t(poly[0]), uint32_t(poly[k]), uint32_t(poly[k + 1])});
  return out;
}

}  // namespace chladni::precompute::cgal_surface
