// Volume meshing: TetGen under -Y and without it, local refinement, bisection, and the quality
// measures.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "chladni/core/error.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/precompute/tet_mesh.hpp"
#include "fem_fixtures.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

using chladni::test::kMeshes;

}  // namespace

TEST(Tetrahedralize, PreservesTheSurfaceAndFillsTheVolume) {
  const SurfaceMesh s = read_mesh(kMeshes + "/bar.obj");
  TetOptions o;
  o.max_volume = 2e-7;
  const TetMesh t = tetrahedralize(s, o);
  ASSERT_EQ(t.surface_vertices, s.vertices.size());
  for (std::size_t v = 0; v < s.vertices.size(); ++v) ASSERT_EQ(t.nodes[v], s.vertices[v]);
  // The faces of exactly one tet are the input triangles, and no tet node lies outside them
  // on the surface.
  std::map<std::array<uint32_t, 3>, int> faces;
  for (const auto& tet : t.tets)
    for (int k = 0; k < 4; ++k) {
      std::array<uint32_t, 3> f{tet[(k + 1) % 4], tet[(k + 2) % 4], tet[(k + 3) % 4]};
      std::sort(f.begin(), f.end());
      ++faces[f];
    }
  std::set<std::array<uint32_t, 3>> boundary, input;
  for (const auto& [f, n] : faces)
    if (n == 1) boundary.insert(f);
  for (auto f : s.triangles) {
    std::sort(f.begin(), f.end());
    input.insert(f);
  }
  EXPECT_EQ(boundary, input);
  const TetQuality q = tet_quality(t);
  EXPECT_NEAR(q.volume, 9e-5, 1e-12);
  EXPECT_LE(q.max_radius_edge, 2.0);
  EXPECT_GT(q.min_dihedral_deg, 5.0);
  // Volume bound honoured (TetGen's -a).
  const double max_v = 2e-7 * (1 + 1e-9);
  for (std::size_t e = 0; e < t.tets.size(); ++e) {
    ASSERT_GT(tet_volume(t, e), 0);
    ASSERT_LE(tet_volume(t, e), max_v);
  }
}

// Local refinement (TetGen -r): the tetrahedra given a bound are split until they meet it, the
// others are left nearly alone, the nodes are kept in order, the volume is still filled, and
// the new boundary is closed and outward (its divergence integral is the volume).
TEST(Tetrahedralize, RefineTetsRefinesWhereAskedAndKeepsTheNodes) {
  TetOptions o;
  o.max_volume = 2e-5;
  const TetMesh t = tetrahedralize(test::box_surface({0.3, 0.1, 0.1}, {3, 1, 1}), o);
  auto centre_x = [](const TetMesh& m, std::size_t e) {
    double x = 0;
    for (uint32_t v : m.tets[e]) x += m.nodes[v][0] / 4;
    return x;
  };
  std::vector<double> bound(t.tets.size(), -1.0);
  std::size_t right = 0;
  for (std::size_t e = 0; e < t.tets.size(); ++e) {
    if (centre_x(t, e) < 0.1) bound[e] = tet_volume(t, e) / 8;
    if (centre_x(t, e) > 0.2) ++right;
  }
  const TetMesh r = refine_tets(t, bound, o);
  ASSERT_GE(r.nodes.size(), t.nodes.size());
  for (std::size_t v = 0; v < t.nodes.size(); ++v) ASSERT_EQ(r.nodes[v], t.nodes[v]);
  EXPECT_EQ(r.surface_vertices, t.surface_vertices);
  std::size_t left_after = 0, right_after = 0, left_before = 0;
  double volume = 0;
  for (std::size_t e = 0; e < r.tets.size(); ++e) {
    const double v = tet_volume(r, e);
    ASSERT_GT(v, 0);
    volume += v;
    if (centre_x(r, e) < 0.1) ++left_after;
    if (centre_x(r, e) > 0.2) ++right_after;
  }
  for (std::size_t e = 0; e < t.tets.size(); ++e) left_before += centre_x(t, e) < 0.1;
  EXPECT_NEAR(volume, 0.003, 1e-12);
  EXPECT_GT(left_after, 4 * left_before) << left_before;
  EXPECT_LT(right_after, 2 * right) << right;  // grading spills over a little, no more
  const TetQuality q = tet_quality(r);
  EXPECT_GT(q.min_dihedral_deg, 5.0);
  // Closed and outward: every edge in two boundary faces, in opposite directions, and the
  // divergence theorem on x gives the volume.
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  double div = 0;
  for (const auto& f : r.surface_triangles) {
    for (int k = 0; k < 3; ++k) ++edges[{f[k], f[(k + 1) % 3]}];
    const Vec3 &a = r.nodes[f[0]], &b = r.nodes[f[1]], &c = r.nodes[f[2]];
    div += (a[0] + b[0] + c[0]) / 3 * cross(sub(b, a), sub(c, a))[0] / 2;
  }
  for (const auto& [e, n] : edges) {
    ASSERT_EQ(n, 1);
    ASSERT_EQ(edges.count({e.second, e.first}), 1u);
  }
  EXPECT_NEAR(div, 0.003, 1e-12);
  EXPECT_THROW(refine_tets(t, std::vector<double>(3, 1.0), o), InternalError);
}

// Every face in one tetrahedron (on the boundary) or in two, oppositely turned; the boundary
// faces all on the sides of the box `r` fills, enclosing `volume` by the divergence theorem on x.
void expect_conforming_and_closed(const TetMesh& r, double volume) {
  std::map<std::array<uint32_t, 3>, std::vector<std::array<uint32_t, 3>>> faces;
  for (const auto& q : r.tets)
    for (int skip = 0; skip < 4; ++skip) {
      // Turned like the tet's boundary (outward): even permutations of the other three.
      static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
      std::array<uint32_t, 3> f{q[kFace[skip][0]], q[kFace[skip][1]], q[kFace[skip][2]]}, key = f;
      std::sort(key.begin(), key.end());
      faces[key].push_back(f);
    }
  std::size_t boundary = 0;
  for (const auto& [key, list] : faces) {
    ASSERT_LE(list.size(), 2u);
    if (list.size() == 1) {
      ++boundary;
      continue;
    }
    const auto &a = list[0], &b = list[1];  // opposite turns: b is a odd permutation of a
    const bool same = (a == b) || (a[0] == b[1] && a[1] == b[2] && a[2] == b[0]) ||
                      (a[0] == b[2] && a[1] == b[0] && a[2] == b[1]);
    EXPECT_FALSE(same) << "two tetrahedra on the same side of a face";
  }
  // A face cut one way on one side and another way on the other would show up as faces of one
  // tetrahedron inside the box: every face of one must lie on the box's surface.
  EXPECT_EQ(boundary, r.surface_triangles.size());
  Vec3 lo = r.nodes[0], hi = r.nodes[0];
  for (const Vec3& p : r.nodes)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  double div = 0;
  for (const auto& f : r.surface_triangles) {
    const Vec3 &a = r.nodes[f[0]], &b = r.nodes[f[1]], &c = r.nodes[f[2]];
    bool on_side = false;
    for (int k = 0; k < 3; ++k)
      for (double side : {lo[k], hi[k]}) on_side |= a[k] == side && b[k] == side && c[k] == side;
    ASSERT_TRUE(on_side) << "a boundary face inside the box: nodes " << f[0] << " " << f[1] << " "
                         << f[2];
    div += (a[0] + b[0] + c[0]) / 3 * cross(sub(b, a), sub(c, a))[0] / 2;
  }
  EXPECT_NEAR(div, volume, 1e-12);
}

// Bisection: each child lies in one tetrahedron of the input (found by its centroid), the
// children of each input tetrahedron fill it exactly and meet its bound, the mesh is conforming
// (every face in one tetrahedron on the boundary or in two, oppositely turned) and closed, and
// the quality of the input is not lost.
TEST(Tetrahedralize, BisectTetsMeetsTheBoundsConformingAndKeepsTheNodes) {
  TetOptions o;
  o.max_volume = 2e-5;
  const TetMesh t = tetrahedralize(test::box_surface({0.3, 0.1, 0.1}, {3, 1, 1}), o);
  std::vector<double> bound(t.tets.size(), -1.0);
  for (std::size_t e = 0; e < t.tets.size(); ++e) {
    double x = 0;
    for (uint32_t v : t.tets[e]) x += t.nodes[v][0] / 4;
    if (x < 0.1) bound[e] = tet_volume(t, e) / (e % 2 ? 8 : 3);  // 3 and 2 halvings
  }
  const TetMesh r = bisect_tets(t, bound);
  ASSERT_GT(r.tets.size(), t.tets.size());
  for (std::size_t v = 0; v < t.nodes.size(); ++v) ASSERT_EQ(r.nodes[v], t.nodes[v]);
  EXPECT_EQ(r.surface_vertices, t.surface_vertices);
  auto contains = [&](std::size_t e, const Vec3& p) {  // barycentric signs of p in tet e
    const auto& q = t.tets[e];
    for (int k = 0; k < 4; ++k) {
      TetMesh probe{t.nodes, {q}, 0, {}};
      probe.nodes.push_back(p);
      probe.tets[0][k] = uint32_t(probe.nodes.size() - 1);
      if (tet_volume(probe, 0) < -1e-15) return false;
    }
    return true;
  };
  std::vector<double> filled(t.tets.size(), 0.0);
  std::vector<std::size_t> children(t.tets.size(), 0);
  for (std::size_t c = 0; c < r.tets.size(); ++c) {
    const double v = tet_volume(r, c);
    ASSERT_GT(v, 0) << "child " << c;
    Vec3 centre{0, 0, 0};
    for (uint32_t n : r.tets[c])
      for (int k = 0; k < 3; ++k) centre[k] += r.nodes[n][k] / 4;
    std::size_t parent = t.tets.size();
    for (std::size_t e = 0; e < t.tets.size() && parent == t.tets.size(); ++e)
      if (contains(e, centre)) parent = e;
    ASSERT_LT(parent, t.tets.size()) << "child " << c << " outside the input";
    filled[parent] += v;
    ++children[parent];
    if (bound[parent] > 0) {
      EXPECT_LE(v, bound[parent] * (1 + 1e-12)) << "child " << c;
    }
  }
  std::size_t split_unmarked = 0;
  for (std::size_t e = 0; e < t.tets.size(); ++e) {
    EXPECT_NEAR(filled[e], tet_volume(t, e), 1e-15) << "input tet " << e;
    if (bound[e] <= 0 && children[e] > 1) ++split_unmarked;
  }
  EXPECT_GT(split_unmarked, 0u);                // conformity reaches past the marked region ...
  EXPECT_LT(r.tets.size(), 8 * t.tets.size());  // ... but not over the whole box
  expect_conforming_and_closed(r, 0.003);
  EXPECT_GT(tet_quality(r).min_dihedral_deg, 0.5 * tet_quality(t).min_dihedral_deg);
  EXPECT_EQ(bisect_tets(t, std::vector<double>(t.tets.size(), -1.0)).tets.size(), t.tets.size());
  EXPECT_THROW(bisect_tets(t, std::vector<double>(3, 1.0)), InternalError);
}

// Where TetGen's -Y (the input's triangles kept as the boundary) leaves flat tetrahedra, the
// solid is meshed again with points added on the surface: a better worst angle, the input's
// vertices first and in order, then the added surface points, each on an input triangle, and a
// boundary that is closed, outward and encloses the same volume.
TEST(Tetrahedralize, FlatMeshesAreMadeAgainWithPointsOnTheSurface) {
  const SurfaceMesh s = read_mesh(kMeshes + "/rotor.obj");
  TetOptions o;
  o.max_volume = coarse_max_volume(s);
  const TetMesh kept = tetrahedralize(s, o);
  const double worst = tet_quality(kept).min_dihedral_deg;
  ASSERT_LT(worst, 1.0);  // the rotor's own triangles force slivers
  o.flat_dihedral_deg = 1.0;
  std::size_t seen = 0;
  o.before_remesh = [&](const TetMesh& flat) { seen = flat.tets.size(); };
  const TetMesh t = tetrahedralize(s, o);
  EXPECT_EQ(seen, kept.tets.size());  // the flat mesh is shown before it is made again
  EXPECT_GT(t.tets.size(), seen);
  TetOptions refuse = o;
  refuse.before_remesh = [](const TetMesh&) { throw BudgetError("over"); };
  EXPECT_THROW(tetrahedralize(s, refuse), BudgetError);
  const TetQuality q = tet_quality(t);
  EXPECT_GT(q.min_dihedral_deg, worst);
  // TetGen merges nearly coplanar input triangles into one facet and places points on it: all
  // but one of the rotor's within 1e-6 of its size of the surface, that one 1.2e-5.
  EXPECT_NEAR(q.volume, tet_quality(kept).volume, 1e-6 * q.volume);
  // The input, as split to the bound, first.
  ASSERT_GT(t.surface_vertices, kept.surface_vertices);
  for (std::size_t v = 0; v < kept.surface_vertices; ++v) ASSERT_EQ(t.nodes[v], kept.nodes[v]);
  // The surface triangles are the boundary faces, over exactly the first surface_vertices nodes.
  auto sorted = [](std::vector<std::array<uint32_t, 3>> f) {
    for (auto& x : f) std::sort(x.begin(), x.end());
    std::sort(f.begin(), f.end());
    return f;
  };
  EXPECT_EQ(sorted(t.surface_triangles), sorted(boundary_faces(t)));
  std::vector<bool> on_surface(t.nodes.size(), false);
  for (const auto& f : t.surface_triangles)
    for (uint32_t v : f) on_surface[v] = true;
  for (std::size_t v = 0; v < t.nodes.size(); ++v)
    ASSERT_EQ(on_surface[v], v < t.surface_vertices) << v;
  // Closed and outward: the divergence theorem gives the volume back.
  double divergence = 0;
  for (const auto& f : t.surface_triangles)
    divergence += dot(t.nodes[f[0]], cross(t.nodes[f[1]], t.nodes[f[2]])) / 6;
  EXPECT_NEAR(divergence, q.volume, 1e-9 * q.volume);
  // Each added point lies on an input triangle (to TetGen's facet merging, above).
  const double size = std::cbrt(q.volume);
  for (std::size_t v = kept.surface_vertices; v < t.surface_vertices; ++v) {
    double nearest = INFINITY;
    for (const auto& f : s.triangles) {
      const Vec3 a = s.vertices[f[0]], e1 = sub(s.vertices[f[1]], a), e2 = sub(s.vertices[f[2]], a);
      const Vec3 n = cross(e1, e2), d = sub(t.nodes[v], a);
      const double nn = dot(n, n);
      const double b1 = dot(cross(d, e2), n) / nn, b2 = dot(cross(e1, d), n) / nn;
      if (b1 >= -1e-6 && b2 >= -1e-6 && b1 + b2 <= 1 + 1e-6)
        nearest = std::min(nearest, std::abs(dot(d, n)) / std::sqrt(nn));
    }
    const bool found = nearest < 1e-4 * size;
    ASSERT_TRUE(found) << "added surface point " << v << " is " << nearest / size << " off";
  }
}

// Where the surface's triangles leave most -Y tetrahedra poorly shaped (the CAD rotor's mean
// radius-edge ratio is 6.5, against 1.05-1.35 for meshes from good surfaces), meshing without
// keep_surface adds points on the surface: well-shaped tetrahedra filling the same solid, the
// surface's vertices first.
TEST(Tetrahedralize, PoorlyShapedMeshesAreMadeAgainWithPointsOnTheSurface) {
  const SurfaceMesh rotor = read_mesh(kMeshes + "/rotor.obj");
  TetOptions keep;  // by default the input triangles are the boundary
  keep.max_volume = coarse_max_volume(rotor);
  const TetMesh y = tetrahedralize(rotor, keep);
  const TetQuality yq = tet_quality(y);
  ASSERT_GT(yq.mean_radius_edge, 3.0);
  TetOptions o;
  o.max_volume = keep.max_volume;
  o.keep_surface = false;
  const TetMesh t = tetrahedralize(rotor, o);
  const TetQuality q = tet_quality(t);
  EXPECT_LT(q.mean_radius_edge, kPoorMeanRadiusEdge);
  EXPECT_GT(q.min_dihedral_deg, yq.min_dihedral_deg);
  EXPECT_GT(t.surface_vertices, y.surface_vertices);
  EXPECT_NEAR(q.volume, yq.volume, 1e-6 * yq.volume);
  // The surface's vertices come first and in order, the added ones after them.
  for (std::size_t v = 0; v < rotor.vertices.size(); ++v) ASSERT_EQ(t.nodes[v], y.nodes[v]) << v;
  // Its boundary covers the same surface: the same area.
  auto area = [](const TetMesh& m) {
    double a = 0;
    for (const auto& f : m.surface_triangles)
      a += 0.5 * norm(cross(sub(m.nodes[f[1]], m.nodes[f[0]]), sub(m.nodes[f[2]], m.nodes[f[0]])));
    return a;
  };
  EXPECT_NEAR(area(t), area(y), 1e-6 * area(y));
}

// A CAD box exports each face as two triangles: a 0.4 m x 4 mm face gives needles. Splitting
// them alone keeps needles (about 50,000 tetrahedra with dihedral angles of 0.1 degrees here);
// flipped within their plane they become a strip of well-shaped triangles, and the solid a few
// hundred well-shaped tetrahedra, with the surface and the volume unchanged.
TEST(Tetrahedralize, NeedleTrianglesOfACadBoxAreReshapedWithinTheirPlanes) {
  const Vec3 size{0.4, 0.004, 0.004};
  const SurfaceMesh rod = test::box_surface(size, {1, 1, 1});
  ASSERT_EQ(rod.triangles.size(), 12u);
  TetOptions o;
  o.max_volume = size[0] * size[1] * size[2] / 300;
  const TetMesh t = tetrahedralize(rod, o);
  const TetQuality q = tet_quality(t);
  EXPECT_NEAR(q.volume, 6.4e-6, 1e-15);
  EXPECT_LT(q.max_radius_edge, 2.0);
  EXPECT_GT(q.min_dihedral_deg, 10.0);
  EXPECT_LT(t.tets.size(), 3000u);
  const double edge = 1.5 * std::cbrt(6 * std::numbers::sqrt2 * o.max_volume);
  for (const auto& f : t.surface_triangles) {
    const Vec3 p[3] = {t.nodes[f[0]], t.nodes[f[1]], t.nodes[f[2]]};
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = sub(p[(k + 1) % 3], p[k]), w = sub(p[(k + 2) % 3], p[k]);
      const Vec3 c = cross(u, w);
      ASSERT_LE(std::sqrt(dot(u, u)), edge * (1 + 1e-12));
      ASSERT_GT(std::atan2(std::sqrt(dot(c, c)), dot(u, w)), 20 * std::numbers::pi / 180);
    }
  }
  for (std::size_t v = 0; v < t.surface_vertices; ++v) {  // on a face of the box
    int on = 0;
    for (int k = 0; k < 3; ++k)
      on += std::abs(t.nodes[v][k]) < 1e-15 || std::abs(t.nodes[v][k] - size[k]) < 1e-15;
    ASSERT_GE(on, 1) << "surface node " << v;
  }
}

// The corner tetrahedron of a cube: right angles at its three axis edges, acos(1/sqrt 3) at the
// others, and radius-edge sqrt(3)/2 / 1.
TEST(Tetrahedralize, QualityOfACornerTetrahedron) {
  TetMesh m;
  m.nodes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.tets = {{0, 1, 2, 3}};
  const TetQuality q = tet_quality(m);
  EXPECT_NEAR(q.min_dihedral_deg, std::acos(1 / std::sqrt(3.0)) * 180 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(q.max_dihedral_deg, 90, 1e-9);
  EXPECT_NEAR(q.max_radius_edge, std::sqrt(3.0) / 2, 1e-12);
  EXPECT_NEAR(q.volume, 1.0 / 6, 1e-15);
}
