// The validity checks on good and broken meshes, repair, and the automatic tetrahedron size.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "chladni/core/error.hpp"
#include "chladni/precompute/mesh_repair.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/precompute/tet_mesh.hpp"
#include "fem_fixtures.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

using chladni::test::kMeshes;

// Unit cube, outward counter-clockwise triangles.
const double kCubeV[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                             {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kCubeF[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                           {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

std::string cube_obj() {
  std::string s = "# cube\n";
  for (auto& v : kCubeV)
    s += "v " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) +
         "\n";
  for (auto& f : kCubeF)
    s += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " +
         std::to_string(f[2] + 1) + "\n";
  return s;
}

// One file per test process: ctest runs these tests in parallel, and one writing the file while
// another reads it gave "holds no faces".
SurfaceMesh cube() {
  return read_mesh(
      chladni::test::write_temp("chladni_cube_" + std::to_string(::getpid()) + ".obj", cube_obj()));
}

std::string message_of(const SurfaceMesh& m) {
  try {
    require_valid(check_mesh(m), "m.obj", false);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MeshCheck, BundledMeshesAreValidSolids) {
  for (const char* name : {"bar.obj", "bowl.obj", "rotor.obj", "coupling.obj"}) {
    const SurfaceMesh m = read_mesh(kMeshes + "/" + name);
    const MeshReport r = check_mesh(m);
    EXPECT_TRUE(r.ok()) << name << ": " << message_of(m);
    EXPECT_TRUE(r.self_intersections_checked) << name;
    EXPECT_EQ(r.components, 1u) << name;
  }
  EXPECT_NEAR(check_mesh(read_mesh(kMeshes + "/bar.obj")).volume, 9e-5, 1e-9);
}

TEST(MeshCheck, ElephantWithHolesIsRefusedWithCountsAndEdges) {
  const SurfaceMesh m = read_mesh(kMeshes + "/broken/elephant_with_holes.obj");
  const MeshReport r = check_mesh(m);
  EXPECT_EQ(r.boundary_edges, 1353u);
  EXPECT_EQ(r.self_intersections, 173u);
  const std::string msg = message_of(m);
  EXPECT_NE(msg.find("not closed: 1353 boundary edges"), std::string::npos) << msg;
  EXPECT_NE(msg.find("e.g. edges "), std::string::npos) << msg;
  EXPECT_NE(msg.find("try --repair"), std::string::npos) << msg;
}

TEST(MeshCheck, SelfIntersectingTeapotIsRefusedWithFacePairs) {
  const SurfaceMesh m = read_mesh(kMeshes + "/broken/teapot_solid_selfintersecting.obj");
  const MeshReport r = check_mesh(m);
  EXPECT_EQ(r.boundary_edges, 0u);
  EXPECT_EQ(r.inconsistent_edges, 0u);
  EXPECT_GT(r.volume, 0);
  EXPECT_EQ(r.self_intersections, 35u);
  EXPECT_NE(message_of(m).find("35 pairs of faces intersect, e.g. faces ("), std::string::npos);
}

TEST(MeshCheck, OrientationManifoldnessAndDegeneracyProblemsAreNamed) {
  SurfaceMesh m = cube();
  for (auto& t : m.triangles) std::swap(t[1], t[2]);  // all inward
  EXPECT_NE(message_of(m).find("signed volume"), std::string::npos);
  m = cube();
  std::swap(m.triangles[3][1], m.triangles[3][2]);  // one face flipped
  EXPECT_NE(message_of(m).find("inconsistently oriented: 3 edges"), std::string::npos)
      << message_of(m);
  m = cube();
  m.triangles.push_back({0, 1, 6});  // a fin: edge 0-1 now in three faces
  EXPECT_NE(message_of(m).find("edges shared by more than two faces"), std::string::npos);
  m = cube();
  m.vertices.push_back({0.5, 0, 0});
  m.triangles.push_back({0, 1, 8});  // zero area
  EXPECT_NE(message_of(m).find("degenerate faces (zero area), e.g. faces 12"), std::string::npos);
  // Two cubes sharing only vertex 6: two pieces, one non-manifold vertex.
  m = cube();
  const SurfaceMesh c2 = cube();
  for (const Vec3& v : c2.vertices) m.vertices.push_back({v[0] + 1, v[1] + 1, v[2] + 1});
  for (auto t : c2.triangles) {
    for (auto& i : t) i = i == 0 ? 6 : i + 8;
    m.triangles.push_back(t);
  }
  const std::string two = message_of(m);
  EXPECT_NE(two.find("vertices whose faces form more than one fan, e.g. vertices 6"),
            std::string::npos)
      << two;
}

TEST(MeshRepair, FixesOrientationAndReportsIt) {
  SurfaceMesh m = cube();
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  const auto log = repair_mesh(m).log;
  EXPECT_TRUE(check_mesh(m).ok()) << message_of(m);
  ASSERT_FALSE(log.empty());
  EXPECT_NE(log.back().find("reversed"), std::string::npos);
}

TEST(MeshRepair, StitchesDuplicatedVertices) {
  // Every triangle with its own three vertices (as in STL files).
  SurfaceMesh c = cube(), m;
  for (const auto& t : c.triangles) {
    const uint32_t base = uint32_t(m.vertices.size());
    for (uint32_t v : t) m.vertices.push_back(c.vertices[v]);
    m.triangles.push_back({base, base + 1, base + 2});
  }
  EXPECT_EQ(check_mesh(m).boundary_edges, 36u);
  const auto log = repair_mesh(m).log;
  EXPECT_TRUE(check_mesh(m).ok()) << message_of(m);
  EXPECT_EQ(m.vertices.size(), 8u);
}

TEST(MeshRepair, BrokenSampleMeshesBecomeValidSolids) {
  for (const char* name : {"elephant_with_holes.obj", "teapot_solid_selfintersecting.obj"}) {
    SurfaceMesh m = read_mesh(kMeshes + std::string("/broken/") + name);
    const auto log = repair_mesh(m).log;
    EXPECT_FALSE(log.empty()) << name;
    const MeshReport r = check_mesh(m);
    EXPECT_TRUE(r.ok()) << name << ": " << message_of(m);
  }
}

TEST(Tetrahedralize, AutoSizeShrinksWithFrequencyAndOrder) {
  const SurfaceMesh s = cube();  // 1 m: the wavelength bound, not the box bound, decides
  const Material steel = find_material("steel");
  const double v1 = auto_max_volume(steel, 5000, 1, s), v2 = auto_max_volume(steel, 5000, 2, s);
  EXPECT_NEAR(v1 / v2, 1.0 / 8, 1e-12);  // half the edge length for linear elements
  EXPECT_NEAR(auto_max_volume(steel, 10000, 2, s) / v2, 1.0 / 8, 1e-12);
}

TEST(MeshFixtures, GeneratedBoxAndSphereAreValidSolids) {
  const SurfaceMesh box = test::box_surface({0.3, 0.03, 0.01}, {30, 3, 2});
  const MeshReport r = check_mesh(box);
  EXPECT_TRUE(r.ok()) << message_of(box);
  EXPECT_NEAR(r.volume, 9e-5, 1e-15);
  const SurfaceMesh s = test::icosphere(0.1, 2);
  const MeshReport rs = check_mesh(s);
  EXPECT_TRUE(rs.ok()) << message_of(s);
  EXPECT_NEAR(rs.volume, 4.0 / 3 * M_PI * 1e-3, 0.05 * 4.0 / 3 * M_PI * 1e-3);  // facets cut 3.4%
}
