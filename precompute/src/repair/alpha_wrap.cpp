// Rung 3 of the repair ladder: CGAL's 3D Alpha Wrapping.
#include <CGAL/alpha_wrap_3.h>

#include <algorithm>

#include "../surface/cgal_surface.hpp"
#include "repair_steps.hpp"

namespace chladni::precompute::repair {
namespace {
using cgal_surface::Mesh, cgal_surface::Point;

}  // namespace

SurfaceMesh alpha_wrap(const SurfaceMesh& soup, double alpha, double offset) {
  const std::vector<Point> points = cgal_surface::to_points(soup);
  std::vector<std::array<std::size_t, 3>> faces;
  faces.reserve(soup.triangles.size());
  for (const auto& t : soup.triangles) faces.push_back({t[0], t[1], t[2]});
  Mesh wrap;
  CGAL::alpha_wrap_3(points, faces, alpha, offset, wrap);
  return cgal_surface::from_mesh(wrap);
}

}  // namespace chladni::precompute::repair
