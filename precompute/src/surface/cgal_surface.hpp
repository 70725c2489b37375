#pragma once
// A SurfaceMesh as CGAL's polygon soup: the types and conversions the two CGAL units
// (mesh_check.cpp, local_thickness.cpp) share. Include it from those units only.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
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

}  // namespace chladni::precompute::cgal_surface
