// Boundary elements finer than the surface (BemSurface): the split keeps the geometry, the
// orientation and each element's place in its parent; the wavelength rule picks the level; and
// the far field converges as the elements halve, on the same faceted surface and velocity.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <string>

#include "chladni/core/error.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/precompute/bem.hpp"
#include "fem_fixtures.hpp"

namespace chladni {
namespace {

using cd = std::complex<double>;

Vec3 area_vector(const precompute::SurfaceMesh& m, std::size_t t) {
  const auto& v = m.vertices;
  const auto& f = m.triangles[t];
  return scale(cross(sub(v[f[1]], v[f[0]]), sub(v[f[2]], v[f[0]])), 0.5);
}

TEST(BemRefine, SplitKeepsGeometryOrientationAndParents) {
  const test::SurfaceMesh base = test::icosphere(0.1, 2);
  const precompute::BemSurface two(base, 2);
  ASSERT_EQ(two.mesh.triangles.size(), 16 * base.triangles.size());
  ASSERT_EQ(two.parent.size(), two.mesh.triangles.size());
  // Shared edges share their midpoints: a closed mesh with V - E + F = 2 (E = 3F/2).
  EXPECT_EQ(double(two.mesh.vertices.size()) - 1.5 * double(two.mesh.triangles.size()) +
                double(two.mesh.triangles.size()),
            2.0);
  std::vector<Vec3> per_parent(base.triangles.size(), Vec3{0, 0, 0});
  for (std::size_t j = 0; j < two.mesh.triangles.size(); ++j) {
    const uint32_t p = two.parent[j];
    const auto& pt = base.triangles[p];
    for (int c = 0; c < 3; ++c) {
      // The corner's barycentric coordinates in the parent give its position.
      Vec3 x{0, 0, 0};
      for (int d = 0; d < 3; ++d) x = add(x, scale(base.vertices[pt[d]], two.corners[j][c][d]));
      const Vec3 y = two.mesh.vertices[two.mesh.triangles[j][c]];
      EXPECT_LT(norm(sub(x, y)), 1e-12) << "element " << j << " corner " << c;
    }
    per_parent[p] = add(per_parent[p], area_vector(two.mesh, j));
  }
  // The children tile their parent exactly, with its orientation.
  for (std::size_t p = 0; p < base.triangles.size(); ++p)
    EXPECT_LT(norm(sub(per_parent[p], area_vector(base, p))), 1e-12 * norm(area_vector(base, p)));
}

// A sphere-harmonic velocity (P_2, linear on the coarse triangles) on a coarse icosphere at
// ka = 12, where its own triangles give two per wavelength: the wavelength rule splits them
// twice, and each halving of the elements moves the far field by under 0.5 dB off the nodal
// cones (the criterion docs/transfer.md holds real assets to).
TEST(BemRefine, FarFieldConvergesAsTheElementsHalve) {
  const double a = 0.1, k = 12.0 / a;
  const test::SurfaceMesh s = test::icosphere(a, 2);
  precompute::AcousticOptions o;
  const precompute::RadiatingSurface surf(s, o);
  EXPECT_EQ(precompute::bem_level(surf, k, o), 2);
  EXPECT_EQ(precompute::bem_level(surf, 0.25 * k, o), 0);
  o.bem_extra_levels = 1;  // every element halved once more
  EXPECT_EQ(precompute::bem_level(surf, 0.25 * k, o), 1);
  EXPECT_EQ(precompute::bem_level(surf, k, o), -1) << "20,480 elements: over auto's cap";
  o.method = precompute::AcousticOptions::Method::Bem;
  EXPECT_EQ(precompute::bem_level(surf, k, o), 3);
  o = {};
  o.bem_auto_elements = s.triangles.size();  // no room to split: the wave solve takes over,
  EXPECT_EQ(precompute::bem_level(surf, k, o), -1);
  EXPECT_EQ(precompute::resolve_method(surf, k, o), precompute::AcousticOptions::Method::Wave);
  o.wave.max_memory = 1e6;  // and the fit where its grid does not fit the memory either
  EXPECT_EQ(precompute::resolve_method(surf, k, o), precompute::AcousticOptions::Method::Sources);
  o = {};
  // The memory budget caps the split as the element cap does (icosphere:2 has 320 triangles, so
  // level 1 has 1280 and level 2 5120): auto falls back to sources, a forced BEM takes the finest
  // mesh that fits and refuses, naming the option, when not even the surface's own fits.
  EXPECT_LT(precompute::bem_memory(1280, o.bem), precompute::bem_memory(5120, o.bem));
  o.bem_max_memory = precompute::bem_memory(1280, o.bem);
  EXPECT_EQ(precompute::bem_level(surf, k, o), -1);
  o.method = precompute::AcousticOptions::Method::Bem;
  EXPECT_EQ(precompute::bem_level(surf, k, o), 1);
  o.bem_max_memory = 0.5 * precompute::bem_memory(320, o.bem);
  try {
    precompute::bem_level(surf, k, o);
    ADD_FAILURE() << "a surface over the memory budget was accepted";
  } catch (const BudgetError& e) {
    EXPECT_NE(std::string(e.what()).find("--max-memory"), std::string::npos) << e.what();
  }
  o = {};

  std::vector<cd> un(s.vertices.size());
  for (std::size_t v = 0; v < un.size(); ++v)
    un[v] = std::legendre(2u, s.vertices[v][2] / norm(s.vertices[v]));
  const precompute::NormalVelocity velocity = surf.from_vertex_values(un);
  std::vector<Vec3> pts;
  for (int d = 0; d < 24; ++d) {
    const double th = std::numbers::pi * (d + 0.5) / 24, ph = 0.7 * d;
    pts.push_back(
        scale({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)}, 10 * a));
  }
  std::vector<std::vector<double>> level_db;
  for (int level = 0; level <= 2; ++level) {
    const precompute::BemSurface el(s, level);
    const precompute::BemMesh mesh(el.mesh);
    precompute::BemSolver solver(mesh, o.bem);
    std::vector<cd> c;
    const ModeTransfer mt = precompute::bem_transfer(surf, el, mesh, solver, k, velocity, o, c);
    EXPECT_EQ(mt.sources, el.mesh.triangles.size());
    Transfer t;
    t.centre = surf.centre();
    t.radius = surf.radius();
    t.add_mode(mt, c);
    std::vector<double> db;
    for (const Vec3& x : pts) db.push_back(20 * std::log10(std::abs(t.pressure(0, x))));
    level_db.push_back(db);
  }
  double d01 = 0, d12 = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (std::abs(std::legendre(2u, pts[i][2] / norm(pts[i]))) < 0.2) continue;  // nodal cones
    d01 = std::max(d01, std::abs(level_db[0][i] - level_db[1][i]));
    d12 = std::max(d12, std::abs(level_db[1][i] - level_db[2][i]));
  }
  EXPECT_LT(d01, 0.5);
  EXPECT_LT(d12, 0.5);
  EXPECT_GT(d01 + d12, 0.0);  // the levels are different solves
}

}  // namespace
}  // namespace chladni
