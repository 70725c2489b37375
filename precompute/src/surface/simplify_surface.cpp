#include "simplify_surface.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Surface_mesh_simplification/Edge_collapse_visitor_base.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <algorithm>
#include <functional>
#include <numeric>

#include "cgal_surface.hpp"
#include "chladni/core/error.hpp"
#include "local_thickness.hpp"

namespace chladni::precompute {

namespace {
using cgal_surface::Kernel;
using cgal_surface::Mesh;
namespace SMS = CGAL::Surface_mesh_simplification;
using Triangle = Kernel::Triangle_3;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<
    Kernel, CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::iterator>>>;

double min_angle_cos(const Kernel::Point_3& a, const Kernel::Point_3& b, const Kernel::Point_3& c) {
  // The cosine of the triangle's smallest angle (1 for a degenerate one).
  const Kernel::Point_3* p[3] = {&a, &b, &c};
  double worst = -1;
  for (int k = 0; k < 3; ++k) {
    const auto u = *p[(k + 1) % 3] - *p[k], v = *p[(k + 2) % 3] - *p[k];
    const double l = std::sqrt(u.squared_length() * v.squared_length());
    worst = std::max(worst, l > 0 ? (u * v) / l : 1.0);
  }
  return worst;
}

// A collapse is taken only when every face it moves keeps its orientation, stays near the input
// surface (its corners, edge midpoints and centroid within `envelope` of it: a sampled, cheaper
// test than CGAL's exact polyhedral envelope, which took 8 minutes on 94k triangles) and does
// not get a smallest angle under kMinAngle worse than the face had: slivers on the surface
// become slivers in the tetrahedra, which keep it.
constexpr double kMinAngleCos = 0.9659;  // 15 degrees
constexpr double kShapeWeight = 0.1;     // against CGAL's 0.5 for volume and for boundary

class NearInputFilter {
 public:
  NearInputFilter(const Tree& tree, double envelope) : tree_(tree), e2_(envelope * envelope) {}
  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(
      const Profile& profile, boost::optional<typename Profile::Point> op) const {
    if (!op) return op;
    const auto& vpm = profile.vertex_point_map();
    const Kernel::Point_3& q2 = *op;
    if (!near(q2)) return boost::none;
    const auto& triangles = profile.triangles();
    auto it = triangles.begin();
    if (profile.left_face_exists()) ++it;  // the faces the collapse removes come first
    if (profile.right_face_exists()) ++it;
    for (; it != triangles.end(); ++it) {
      const Kernel::Point_3 &p = get(vpm, it->v0), &q = get(vpm, it->v1), &r = get(vpm, it->v2);
      if (!CGAL::is_positive(CGAL::cross_product(q - p, r - p) *
                             CGAL::cross_product(q2 - p, r - p)))
        return boost::none;
      const double now = min_angle_cos(p, q2, r);
      if (now > kMinAngleCos && now > min_angle_cos(p, q, r)) return boost::none;
      if (!near(CGAL::midpoint(p, q2)) || !near(CGAL::midpoint(r, q2)) ||
          !near(CGAL::centroid(p, q2, r)))
        return boost::none;
    }
    return op;
  }

 private:
  bool near(const Kernel::Point_3& x) const { return tree_.squared_distance(x) <= e2_; }
  const Tree& tree_;
  double e2_;
};

// Progress as the share of the collapses to the target that are done.
struct ProgressVisitor : SMS::Edge_collapse_visitor_base<Mesh> {
  const std::function<void(double)>* fraction = nullptr;
  std::size_t done = 0, planned = 1;
  void OnCollapsed(const Profile&, const Mesh::Vertex_index&) {
    if (*fraction && ++done % 4096 == 0) (*fraction)(std::min(1.0, double(done) / double(planned)));
  }
};
}  // namespace

SurfaceMesh simplify_surface(const SurfaceMesh& surface, std::size_t target_triangles,
                             double envelope, const std::function<void(double)>& fraction) {
  Mesh mesh;
  if (!cgal_surface::to_closed_mesh(surface, mesh))
    throw InputError("the surface is not a closed polygon mesh");
  // A closed triangle mesh has 3/2 edges per face.
  SMS::Count_stop_predicate<Mesh> stop(target_triangles * 3 / 2);
  std::vector<Triangle> input;
  input.reserve(surface.triangles.size());
  for (const auto& t : surface.triangles) {
    const auto& v = surface.vertices;
    input.emplace_back(Kernel::Point_3(v[t[0]][0], v[t[0]][1], v[t[0]][2]),
                       Kernel::Point_3(v[t[1]][0], v[t[1]][1], v[t[1]][2]),
                       Kernel::Point_3(v[t[2]][0], v[t[2]][1], v[t[2]][2]));
  }
  Tree tree(input.begin(), input.end());
  tree.accelerate_distance_queries();
  const NearInputFilter filter(tree, envelope);
  ProgressVisitor visitor;
  visitor.fraction = &fraction;
  visitor.planned = surface.triangles.size() > target_triangles
                        ? (surface.triangles.size() - target_triangles) / 2  // 2 faces each
                        : 1;
  // Lindstrom-Turk's optional shape term, off by CGAL's default, keeps the triangles near
  // equilateral: without it a 375k-triangle copy of spot.obj came down to 10k triangles a
  // twentieth of which had an angle under 12.4 degrees (23 with it), and TetGen made 118,874
  // tetrahedra of them against 32,535.
  const SMS::internal::LindstromTurk_params params(0.5, 0.5, kShapeWeight);
  SMS::edge_collapse(mesh, stop,
                     CGAL::parameters::get_cost(SMS::LindstromTurk_cost<Mesh>(params))
                         .get_placement(SMS::LindstromTurk_placement<Mesh>(params))
                         .filter(filter)
                         .visitor(visitor));
  mesh.collect_garbage();
  return cgal_surface::from_mesh(mesh);
}

double simplification_envelope(const SurfaceMesh& surface, double tolerance, double share) {
  const double thin = thinnest_wall(surface);
  return share * tolerance * thin / 2;
}

}  // namespace chladni::precompute
