// Rungs 1 and 2 of the repair ladder: CGAL Polygon Mesh Processing's local fixes and its
// self-intersection removal.
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/repair.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>

#include <cmath>
#include <cstdio>

#include "../surface/cgal_surface.hpp"
#include "../surface/surface_pieces.hpp"
#include "repair_steps.hpp"

namespace chladni::precompute::repair {
namespace {

using cgal_surface::Mesh, cgal_surface::Point;
namespace PMP = CGAL::Polygon_mesh_processing;

// Fills holes bounded by at most `max_edges` edges (one representative halfedge per cycle).
std::size_t fill_holes(Mesh& mesh, std::size_t max_edges, const Say& say) {
  std::vector<Mesh::Halfedge_index> borders;
  PMP::extract_boundary_cycles(mesh, std::back_inserter(borders));
  std::size_t filled = 0, left = 0, hole_faces = 0;
  for (auto h : borders) {
    std::size_t len = 0;
    for (auto hh : CGAL::halfedges_around_face(h, mesh)) (void)hh, ++len;
    if (len > max_edges) {
      ++left;
      continue;
    }
    std::vector<Mesh::Face_index> added;
    PMP::triangulate_and_refine_hole(mesh, h, std::back_inserter(added), CGAL::Emptyset_iterator());
    hole_faces += added.size();
    ++filled;
  }
  if (filled)
    say("filled " + std::to_string(filled) + " holes with " + std::to_string(hole_faces) +
        " triangles");
  if (left)
    say("left " + std::to_string(left) + " holes larger than " + std::to_string(max_edges) +
        " edges open");
  return filled;
}

// Soup to halfedge mesh when the soup is one; false otherwise (non-manifold left after
// orientation).
bool as_mesh(const SurfaceMesh& m, Mesh& mesh) {
  const auto polys = cgal_surface::to_polygons(m);
  if (!PMP::is_polygon_soup_a_polygon_mesh(polys)) return false;
  PMP::polygon_soup_to_polygon_mesh(cgal_surface::to_points(m), polys, mesh);
  return true;
}

}  // namespace

LocalFixes local_fixes(const SurfaceMesh& input, std::size_t max_hole_edges, const Say& say) {
  std::vector<Point> points = cgal_surface::to_points(input);
  std::vector<std::vector<std::size_t>> polys = cgal_surface::to_polygons(input);
  const std::size_t v0 = points.size(), f0 = polys.size();

  PMP::repair_polygon_soup(points, polys);
  if (points.size() != v0 || polys.size() != f0)
    say("merged duplicate vertices and dropped degenerate or duplicate triangles: " +
        std::to_string(v0) + " -> " + std::to_string(points.size()) + " vertices, " +
        std::to_string(f0) + " -> " + std::to_string(polys.size()) + " triangles");
  const std::size_t v1 = points.size();
  if (!PMP::orient_polygon_soup(points, polys))
    say("oriented the triangles consistently; " + std::to_string(points.size() - v1) +
        " non-manifold vertices were split");
  Mesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, polys, mesh);

  if (const std::size_t n = PMP::stitch_borders(mesh))
    say("stitched " + std::to_string(n) + " pairs of coincident border edges");
  const std::size_t faces_before = mesh.number_of_faces();
  PMP::remove_degenerate_faces(mesh);
  mesh.collect_garbage();
  if (mesh.number_of_faces() != faces_before)
    say("removed " + std::to_string(faces_before - mesh.number_of_faces()) + " degenerate faces");

  LocalFixes out;
  out.holes_filled = fill_holes(mesh, max_hole_edges, say);
  out.closed = CGAL::is_closed(mesh);
  out.surface = cgal_surface::from_mesh(mesh);
  return out;
}

std::size_t remove_self_intersections(SurfaceMesh& m, const Say& say, std::size_t& remaining) {
  Mesh mesh;
  remaining = 0;
  if (!as_mesh(m, mesh)) return 0;
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  if (pairs.empty()) return 0;
  const bool cleaned =
      PMP::experimental::remove_self_intersections(mesh, CGAL::parameters::preserve_genus(false));
  mesh.collect_garbage();
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> after;
  PMP::self_intersections(mesh, std::back_inserter(after));
  remaining = after.size();
  say("self-intersections: " + std::to_string(pairs.size()) + " face pairs -> " +
      std::to_string(after.size()) + (cleaned ? "" : " (CGAL could not remove them all)"));
  m = cgal_surface::from_mesh(mesh);
  return pairs.size();
}

void remesh_needles(SurfaceMesh& m, double min_angle_deg, const Say& say) {
  Mesh mesh;
  if (!as_mesh(m, mesh) || !CGAL::is_closed(mesh)) return;
  double min_angle = 180, edge_sum = 0;
  for (auto f : mesh.faces()) {
    Point p[3];
    int k = 0;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) p[k++] = mesh.point(v);
    for (int c = 0; c < 3; ++c) {
      const auto u = p[(c + 1) % 3] - p[c], w = p[(c + 2) % 3] - p[c];
      const double cosang = u * w / std::sqrt(u.squared_length() * w.squared_length());
      min_angle = std::min(min_angle, std::acos(std::clamp(cosang, -1.0, 1.0)) * 180 / M_PI);
      edge_sum += std::sqrt(u.squared_length());
    }
  }
  if (!(min_angle < min_angle_deg)) return;
  const double target = edge_sum / (3.0 * mesh.number_of_faces());
  const std::size_t before = mesh.number_of_faces();
  PMP::isotropic_remeshing(faces(mesh), target, mesh, CGAL::parameters::number_of_iterations(3));
  mesh.collect_garbage();
  char buf[160];
  std::snprintf(buf, sizeof buf,
                "remeshed the surface isotropically (smallest angle %.2f deg; edge %.3g m): %zu -> "
                "%zu triangles",
                min_angle, target, before, std::size_t(mesh.number_of_faces()));
  say(buf);
  m = cgal_surface::from_mesh(mesh);
}

void orient_pieces(SurfaceMesh& m, const Say& say) {
  const SurfacePieces s = surface_pieces(m);
  if (s.count() > 1 && !s.nested()) return;
  std::vector<bool> flip(s.count(), false);
  std::size_t outer = 0, inner = 0;
  for (std::size_t p = 0; p < s.count(); ++p) {
    const bool odd = s.count() > 1 && s.depth[p] % 2 == 1;
    flip[p] = odd ? s.volume[p] > 0 : s.volume[p] < 0;
    if (flip[p]) ++(odd ? inner : outer);
  }
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    if (flip[s.of_triangle[f]]) std::swap(m.triangles[f][1], m.triangles[f][2]);
  if (outer) say("reversed all faces to point outward");
  if (inner)
    say("reversed the faces of " + (inner == 1
                                        ? std::string("a cavity to point into it")
                                        : std::to_string(inner) + " cavities to point into them"));
}

}  // namespace chladni::precompute::repair
