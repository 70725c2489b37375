// Surface checks with CGAL Polygon Mesh Processing (predicates and self-intersection tests).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
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

}  // namespace

bool MeshReport::encloses_no_volume() const {
  double diag2 = 0;
  for (int k = 0; k < 3; ++k) diag2 += (bbox_max[k] - bbox_min[k]) * (bbox_max[k] - bbox_min[k]);
  return std::abs(volume) <= 1e-9 * diag2 * std::sqrt(diag2);
}

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
    if (encloses_no_volume())
      os << "encloses no volume (signed volume " << volume
         << " m^3): a flat or open sheet, not a solid";
    else
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

}  // namespace chladni::precompute
