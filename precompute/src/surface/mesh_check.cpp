// Surface checks and repairs with CGAL Polygon Mesh Processing (one of the two CGAL units).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_mesh_to_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/repair.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <cmath>
#include <map>
#include <numeric>
#include <sstream>

#include "../union_find.hpp"
#include "cgal_surface.hpp"
#include "chladni/core/error.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "surface_pieces.hpp"

namespace chladni::precompute {
namespace {

using cgal_surface::from_mesh, cgal_surface::to_points, cgal_surface::to_polygons;
using cgal_surface::Kernel, cgal_surface::Mesh, cgal_surface::Point;
namespace PMP = CGAL::Polygon_mesh_processing;
constexpr std::size_t kExamples = 5;

template <class T>
void note(std::vector<T>& examples, const T& item) {
  if (examples.size() < kExamples) examples.push_back(item);
}

std::string edges_text(const std::vector<std::pair<uint32_t, uint32_t>>& e) {
  std::ostringstream os;
  for (std::size_t k = 0; k < e.size(); ++k)
    os << (k ? ", " : "") << e[k].first << "-" << e[k].second;
  return os.str();
}

// Pieces, the signed volume they bound together and, on a closed consistently wound surface,
// their nesting: a piece at odd depth is a cavity when its volume is negative (faces into it),
// one at even depth > 0 lies loose in one.
void classify_pieces(const SurfaceMesh& m, MeshReport& r) {
  const SurfacePieces s = surface_pieces(m);
  r.components = s.count();
  r.volume = std::accumulate(s.volume.begin(), s.volume.end(), 0.0);
  if (!s.nested() || r.boundary_edges || r.non_manifold_edges || r.inconsistent_edges) return;
  for (std::size_t p = 0; p < s.count(); ++p) {
    if (s.depth[p] == 0) {
      ++r.outer_pieces;
    } else if (s.depth[p] % 2 == 0) {
      ++r.loose_pieces;
      note(r.loose_examples, s.first_triangle[p]);
    } else if (s.is_cavity(p)) {
      ++r.cavities;
    } else {
      ++r.outward_inner_pieces;
      note(r.outward_inner_examples, s.first_triangle[p]);
    }
  }
}

// Keeps the piece of most triangles and the cavities directly inside it.
template <class Say>
void keep_largest_solid(SurfaceMesh& m, Say say) {
  const SurfacePieces s = surface_pieces(m);
  if (s.count() < 2) return;
  std::size_t main = s.count();
  for (std::size_t p = 0; p < s.count(); ++p)
    if ((!s.nested() || s.depth[p] == 0) &&
        (main == s.count() || s.triangles[p] > s.triangles[main]))
      main = p;
  std::vector<bool> keep(s.count(), false);
  std::size_t dropped = 0, dropped_faces = 0, cavities = 0;
  for (std::size_t p = 0; p < s.count(); ++p) {
    keep[p] = p == main || (s.nested() && s.depth[p] == 1 && s.parent[p] == int(main));
    cavities += keep[p] && p != main;
    if (!keep[p]) ++dropped, dropped_faces += s.triangles[p];
  }
  if (!dropped) return;
  m = keep_pieces(m, s, keep);
  say("removed " + std::to_string(dropped) + " separate pieces (" + std::to_string(dropped_faces) +
      " triangles), keeping the largest" +
      (cavities == 1 ? " and the cavity inside it"
       : cavities    ? " and the " + std::to_string(cavities) + " cavities inside it"
                     : ""));
}

// Winds each piece of a closed surface to bound the solid: outer pieces outward, cavities (odd
// nesting depth) into themselves.
template <class Say>
void orient_pieces(SurfaceMesh& m, Say say) {
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

}  // namespace

std::vector<std::string> MeshReport::problems() const {
  std::vector<std::string> out;
  auto list = [](const auto& v) {
    std::ostringstream os;
    for (std::size_t k = 0; k < v.size(); ++k) os << (k ? ", " : "") << v[k];
    return os.str();
  };
  if (triangles == 0) out.push_back("no triangles");
  if (nonfinite_vertices)
    out.push_back(std::to_string(nonfinite_vertices) + " non-finite vertices");
  if (degenerate_faces)
    out.push_back(std::to_string(degenerate_faces) + " degenerate faces (zero area), e.g. faces " +
                  list(degenerate_examples));
  if (boundary_edges)
    out.push_back("not closed: " + std::to_string(boundary_edges) +
                  " boundary edges (in one face only), e.g. edges " +
                  edges_text(boundary_examples));
  if (non_manifold_edges)
    out.push_back("not 2-manifold: " + std::to_string(non_manifold_edges) +
                  " edges shared by more than two faces, e.g. " +
                  edges_text(non_manifold_edge_examples));
  if (non_manifold_vertices)
    out.push_back("not 2-manifold: " + std::to_string(non_manifold_vertices) +
                  " vertices whose faces form more than one fan, e.g. vertices " +
                  list(non_manifold_vertex_examples));
  if (inconsistent_edges)
    out.push_back("inconsistently oriented: " + std::to_string(inconsistent_edges) +
                  " edges used twice in the same direction, e.g. " +
                  edges_text(inconsistent_examples));
  if (self_intersections) {
    std::ostringstream os;
    os << self_intersections << " pairs of faces intersect, e.g. faces";
    for (std::size_t k = 0; k < self_intersection_examples.size(); ++k)
      os << (k ? "," : "") << " (" << self_intersection_examples[k].first << ", "
         << self_intersection_examples[k].second << ")";
    out.push_back(os.str());
  }
  const bool topology_ok =
      !boundary_edges && !non_manifold_edges && !inconsistent_edges && triangles;
  const std::size_t separate = outer_pieces ? outer_pieces : components;
  if (separate > 1)
    out.push_back(std::to_string(separate) + " separate pieces (expected one solid)");
  // Pieces are named by one of their faces.
  auto pieces = [&](std::size_t n, const std::vector<std::size_t>& faces) {
    return n == 1 ? "1 piece (the piece of face " + list(faces) + ")"
                  : std::to_string(n) + " pieces (e.g. those of faces " + list(faces) + ")";
  };
  if (outward_inner_pieces)
    out.push_back(pieces(outward_inner_pieces, outward_inner_examples) +
                  " inside the solid wound outward: a cavity's faces must point into the cavity");
  if (loose_pieces)
    out.push_back(pieces(loose_pieces, loose_examples) +
                  " lying loose inside a cavity: make each solid a separate asset");
  if (topology_ok && !(volume > 0)) {
    std::ostringstream os;
    os << "signed volume " << volume << " m^3 is not positive (faces wound inward)";
    out.push_back(os.str());
  }
  return out;
}

namespace {

// Degenerate faces, and directed edge uses: a manifold, consistently oriented closed surface
// uses every edge once in each direction.
void check_edges(const SurfaceMesh& m, const std::vector<Point>& pts, MeshReport& r) {
  std::map<std::pair<uint32_t, uint32_t>, std::pair<int, int>>
      edges;  // (lo, hi) -> (lo->hi, hi->lo)
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    const auto& t = m.triangles[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
        CGAL::collinear(pts[t[0]], pts[t[1]], pts[t[2]])) {
      ++r.degenerate_faces;
      note(r.degenerate_examples, f);
    }
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      const auto key = std::minmax(a, b);
      auto& uses = edges[key];
      (a < b ? uses.first : uses.second)++;
    }
  }
  for (const auto& [e, uses] : edges) {
    const int total = uses.first + uses.second;
    if (total == 1) {
      ++r.boundary_edges;
      note(r.boundary_examples, e);
    } else if (total > 2) {
      ++r.non_manifold_edges;
      note(r.non_manifold_edge_examples, e);
    } else if (uses.first != 1) {
      ++r.inconsistent_edges;
      note(r.inconsistent_examples, e);
    }
  }
}

// Vertex fans: the faces around a manifold vertex are connected through edges at that vertex.
void check_vertex_fans(const SurfaceMesh& m, MeshReport& r) {
  std::vector<std::vector<std::size_t>> around(m.vertices.size());
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    for (uint32_t v : m.triangles[f]) around[v].push_back(f);
  for (uint32_t v = 0; v < around.size(); ++v) {
    const auto& fs = around[v];
    if (fs.size() < 2) continue;
    UnionFind fan(fs.size());
    std::map<uint32_t, std::size_t> via;  // other endpoint -> first local face
    for (std::size_t i = 0; i < fs.size(); ++i)
      for (uint32_t w : m.triangles[fs[i]]) {
        if (w == v) continue;
        auto [it, fresh] = via.emplace(w, i);
        if (!fresh) fan.unite(i, it->second);
      }
    std::size_t groups = 0;
    for (std::size_t i = 0; i < fs.size(); ++i) groups += fan.find(i) == i;
    if (groups > 1) {
      ++r.non_manifold_vertices;
      note(r.non_manifold_vertex_examples, v);
    }
  }
}

}  // namespace

MeshReport check_mesh(const SurfaceMesh& m) {
  MeshReport r;
  r.vertices = m.vertices.size();
  r.triangles = m.triangles.size();
  r.bbox_min = {INFINITY, INFINITY, INFINITY};
  r.bbox_max = {-INFINITY, -INFINITY, -INFINITY};
  for (const Vec3& v : m.vertices) {
    if (!is_finite(v)) {
      ++r.nonfinite_vertices;
      continue;
    }
    for (int k = 0; k < 3; ++k)
      r.bbox_min[k] = std::min(r.bbox_min[k], v[k]), r.bbox_max[k] = std::max(r.bbox_max[k], v[k]);
  }
  if (r.nonfinite_vertices || m.triangles.empty()) return r;
  const std::vector<Point> pts = to_points(m);

  check_edges(m, pts, r);
  classify_pieces(m, r);

  check_vertex_fans(m, r);

  // Self-intersections need a halfedge structure: only when the soup is a valid polygon mesh.
  const auto polys = to_polygons(m);
  if (!r.non_manifold_edges && !r.non_manifold_vertices && !r.inconsistent_edges &&
      !r.degenerate_faces && PMP::is_polygon_soup_a_polygon_mesh(polys)) {
    Mesh mesh;
    PMP::polygon_soup_to_polygon_mesh(pts, polys, mesh);
    std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
    PMP::self_intersections<CGAL::Parallel_if_available_tag>(mesh, std::back_inserter(pairs));
    r.self_intersections_checked = true;
    r.self_intersections = pairs.size();
    for (const auto& [a, b] : pairs)  // faces are created in soup order
      note(r.self_intersection_examples,
           std::make_pair(std::size_t(a.idx()), std::size_t(b.idx())));
  }
  return r;
}

void require_valid(const MeshReport& report, const std::string& origin, bool after_repair) {
  const auto problems = report.problems();
  if (problems.empty()) return;
  std::string msg = origin + ": mesh is not a valid closed solid" +
                    (after_repair ? " even after --repair" : "") + ":";
  for (const std::string& p : problems) msg += "\n  - " + p;
  if (!after_repair) msg += "\n  (try --repair; indices are 0-based)";
  throw InputError(msg);
}

namespace {

// Fills holes bounded by at most `max_edges` edges (one representative halfedge per cycle).
template <class Say>
void fill_holes(Mesh& mesh, std::size_t max_edges, Say say) {
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
}

// Needle and sliver triangles (typical after hole filling and self-intersection removal) force
// sliver tetrahedra; the surface is remeshed isotropically at its mean edge length when any are
// left.
template <class Say>
void remesh_slivers(Mesh& mesh, double min_angle_deg, Say say) {
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
  if (min_angle < min_angle_deg && CGAL::is_closed(mesh)) {
    const double target = edge_sum / (3.0 * mesh.number_of_faces());
    const std::size_t before = mesh.number_of_faces();
    PMP::isotropic_remeshing(faces(mesh), target, mesh, CGAL::parameters::number_of_iterations(3));
    mesh.collect_garbage();
    char buf[160];
    std::snprintf(
        buf, sizeof buf,
        "remeshed the surface isotropically (smallest angle %.2f deg; edge %.3g m): %zu -> "
        "%zu triangles",
        min_angle, target, before, std::size_t(mesh.number_of_faces()));
    say(buf);
  }
}

}  // namespace

std::vector<std::string> repair_mesh(SurfaceMesh& m, const RepairOptions& options) {
  std::vector<std::string> log;
  auto say = [&](const std::string& s) { log.push_back(s); };
  std::vector<Point> points = to_points(m);
  std::vector<std::vector<std::size_t>> polys = to_polygons(m);
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

  fill_holes(mesh, options.max_hole_edges, say);

  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  if (!pairs.empty()) {
    const bool cleaned =
        PMP::experimental::remove_self_intersections(mesh, CGAL::parameters::preserve_genus(false));
    mesh.collect_garbage();
    std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> after;
    PMP::self_intersections(mesh, std::back_inserter(after));
    say("self-intersections: " + std::to_string(pairs.size()) + " face pairs -> " +
        std::to_string(after.size()) + (cleaned ? "" : " (CGAL could not remove them all)"));
  }
  remesh_slivers(mesh, options.min_angle_deg, say);
  const bool closed = CGAL::is_closed(mesh);
  m = from_mesh(mesh);
  keep_largest_solid(m, say);
  if (closed) orient_pieces(m, say);
  return log;
}

}  // namespace chladni::precompute
