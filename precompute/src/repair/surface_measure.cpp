// How far a repair moved a surface and what volume it bounds, on triangle soups (the input may
// be open, non-manifold or self-intersecting), with CGAL's AABB trees.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "repair_steps.hpp"

namespace chladni::precompute::repair {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Triangles = std::vector<Triangle>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

// Sample points on `from` beyond this many are spaced further apart.
constexpr double kMaxSamples = 4e5;
// Samples tested for being seen from outside, about, and the directions each looks in.
constexpr std::size_t kMaxVisibilityTests = 4000;
constexpr int kDirections = 32;

Point point(const Vec3& v) {
  return {v[0], v[1], v[2]};
}

Triangles triangles_of(const SurfaceMesh& m) {
  Triangles t;
  t.reserve(m.triangles.size());
  for (const auto& f : m.triangles) {
    Triangle tri(point(m.vertices[f[0]]), point(m.vertices[f[1]]), point(m.vertices[f[2]]));
    if (!tri.is_degenerate()) t.push_back(tri);
  }
  return t;
}

// Calls visit(p, n) for the corners and, on triangles longer than `spacing`, for a barycentric
// grid of points `spacing` apart, n being the triangle's normal.
template <class Visit>
void sample(const SurfaceMesh& m, double spacing, Visit visit) {
  for (const auto& f : m.triangles) {
    const Vec3 &a = m.vertices[f[0]], &b = m.vertices[f[1]], &c = m.vertices[f[2]];
    const Vec3 n = triangle_normal(a, b, c);
    const double longest = std::max({norm(sub(b, a)), norm(sub(c, b)), norm(sub(a, c))});
    const int k = int(std::min(std::ceil(longest / spacing), 200.0));
    for (int i = 0; i <= k; ++i)
      for (int j = 0; i + j <= k; ++j) {
        const double u = double(i) / k, w = double(j) / k;
        visit(point(add(a, add(scale(sub(b, a), u), scale(sub(c, a), w)))), n);
      }
  }
}

double area_of(const SurfaceMesh& m) {
  double area = 0;
  for (const auto& f : m.triangles)
    area += 0.5 * norm(triangle_normal(m.vertices[f[0]], m.vertices[f[1]], m.vertices[f[2]]));
  return area;
}

}  // namespace

namespace {

// Whether q, on a face of normal n, sees out of the surface: whether a segment from just off
// either side of the face, in one of kDirections directions spread over the sphere (a
// Fibonacci lattice), reaches beyond the surface's box without meeting it.
bool sees_out(const Tree& tree, const Point& q, const Vec3& n, double reach) {
  const double len = norm(n);
  if (!(len > 0)) return true;
  const double eps = 1e-6 * reach;
  for (int i = 0; i < kDirections; ++i) {
    const double z = 1 - (2 * i + 1.0) / kDirections, r = std::sqrt(1 - z * z);
    const double phi = i * 2.399963229728653;  // the golden angle
    const Kernel::Vector_3 dir(r * std::cos(phi), r * std::sin(phi), z);
    const double side = (dir.x() * n[0] + dir.y() * n[1] + dir.z() * n[2]) / len;
    if (std::abs(side) < 0.05) continue;
    const Point from = q + Kernel::Vector_3(n[0], n[1], n[2]) * (side > 0 ? eps / len : -eps / len);
    if (!tree.do_intersect(Kernel::Segment_3(from, from + dir * reach))) return true;
  }
  return false;
}

}  // namespace

double one_sided_distance(const SurfaceMesh& from, const SurfaceMesh& to, double spacing,
                          bool skip_interior) {
  const Triangles tris = triangles_of(to), own = triangles_of(from);
  if (tris.empty() || own.empty()) return INFINITY;
  // Enough points to cover the area at `spacing`, at most kMaxSamples of them.
  spacing = std::max(spacing, std::sqrt(2 * area_of(from) / kMaxSamples));
  Tree tree(tris.begin(), tris.end());
  tree.accelerate_distance_queries();
  std::vector<std::pair<double, std::pair<Point, Vec3>>> far;  // (distance^2, (point, normal))
  sample(from, spacing, [&](const Point& p, const Vec3& n) {
    far.push_back({CGAL::to_double(tree.squared_distance(p)), {p, n}});
  });
  std::sort(far.begin(), far.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  if (!skip_interior) return std::sqrt(far.front().first);
  // The farthest point that can be seen from outside `from`: faces of overlapping parts inside
  // another part, and walls sealed inside by filled holes, are not the solid's surface.
  Tree self(own.begin(), own.end());
  const auto box = self.bbox();
  const double reach =
      4 * std::sqrt(CGAL::squared_distance(Point(box.xmin(), box.ymin(), box.zmin()),
                                           Point(box.xmax(), box.ymax(), box.zmax())));
  // Every stride-th sample, farthest first, then the samples between the first that sees out
  // and the one tested before it: the farthest that sees out, at a bounded number of tests.
  const std::size_t stride = std::max<std::size_t>(1, far.size() / kMaxVisibilityTests);
  auto sees = [&](std::size_t i) {
    return sees_out(self, far[i].second.first, far[i].second.second, reach);
  };
  for (std::size_t i = 0; i < far.size(); i += stride)
    if (sees(i)) {
      for (std::size_t j = i >= stride ? i - stride + 1 : 0; j < i; ++j)
        if (sees(j)) return std::sqrt(far[j].first);
      return std::sqrt(far[i].first);
    }
  return 0;  // nothing of `from` is seen from outside it
  return std::sqrt(far.front().first);
}

double gap_between(const SurfaceMesh& a, const SurfaceMesh& b) {
  const Triangles ta = triangles_of(a), tb = triangles_of(b);
  if (ta.empty() || tb.empty()) return INFINITY;
  Tree tree_a(ta.begin(), ta.end()), tree_b(tb.begin(), tb.end());
  for (const Triangle& t : ta)
    if (tree_b.do_intersect(t)) return 0;
  tree_a.accelerate_distance_queries();
  tree_b.accelerate_distance_queries();
  double gap = INFINITY;
  for (const Vec3& v : a.vertices)
    gap = std::min(gap, CGAL::to_double(tree_b.squared_distance(point(v))));
  for (const Vec3& v : b.vertices)
    gap = std::min(gap, CGAL::to_double(tree_a.squared_distance(point(v))));
  return std::sqrt(gap);
}

namespace {

// Length of the ray's segment from `s` to `e` where the winding number is at least one, or
// nothing when its crossings do not close (it grazed an edge, or the surface is open there).
std::optional<double> inside_length(const Tree& tree, const Point& s, const Point& e) {
  const Kernel::Segment_3 seg(s, e);
  const auto dir = e - s;
  std::vector<std::pair<double, int>> hits;  // (parameter, +1 entering / -1 leaving)
  std::vector<Tree::Intersection_and_primitive_id<Kernel::Segment_3>::Type> found;
  tree.all_intersections(seg, std::back_inserter(found));
  for (const auto& [object, id] : found) {
    const Point* p = boost::get<Point>(&object);
    if (!p) return std::nullopt;  // the ray runs in a face's plane
    const auto n = CGAL::normal(id->vertex(0), id->vertex(1), id->vertex(2));
    const double along = CGAL::to_double(n * dir);
    if (along == 0) return std::nullopt;
    hits.emplace_back(CGAL::to_double((*p - s) * dir), along < 0 ? 1 : -1);
  }
  std::sort(hits.begin(), hits.end());
  int winding = 0;
  double inside = 0, from = 0;
  for (const auto& [t, step] : hits) {
    if (winding >= 1 && winding + step < 1) inside += t - from;
    if (winding < 1 && winding + step >= 1) from = t;
    winding += step;
  }
  if (winding != 0) return std::nullopt;
  return inside / std::sqrt(dir.squared_length());
}

}  // namespace

double union_volume(const SurfaceMesh& m, int rays) {
  const Triangles tris = triangles_of(m);
  if (tris.empty()) return 0;
  Tree tree(tris.begin(), tris.end());
  const auto box = tree.bbox();
  const double lo[3] = {box.xmin(), box.ymin(), box.zmin()};
  const double hi[3] = {box.xmax(), box.ymax(), box.zmax()};
  // Rays along the shortest side: fewest crossings per ray.
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] < hi[axis] - lo[axis]) axis = k;
  const int u = (axis + 1) % 3, w = (axis + 2) % 3;
  const double du = (hi[u] - lo[u]) / rays, dw = (hi[w] - lo[w]) / rays;
  const double margin = 0.01 * (hi[axis] - lo[axis]) + 1e-12;
  double length = 0;
  int counted = 0;
  for (int i = 0; i < rays; ++i)
    for (int j = 0; j < rays; ++j) {
      // Irrational offsets inside each cell keep rays off the grid lines CAD edges lie on; a
      // ray that still grazes an edge is cast again a little aside.
      for (double jitter : {0.0, 0.1372, -0.2113}) {
        double s[3], e[3];
        s[u] = e[u] = lo[u] + (i + 0.5 + 0.0731 + jitter) * du;
        s[w] = e[w] = lo[w] + (j + 0.5 - 0.0413 + jitter) * dw;
        s[axis] = lo[axis] - margin, e[axis] = hi[axis] + margin;
        if (const auto l = inside_length(tree, Point(s[0], s[1], s[2]), Point(e[0], e[1], e[2]))) {
          length += *l;
          ++counted;
          break;
        }
      }
    }
  if (!counted) return 0;
  return length * du * dw * (double(rays) * rays / counted);
}

}  // namespace chladni::precompute::repair
