// Boundary elements: the element integrals against closed forms (self terms, solid angle), the
// Burton-Miller solve and its multipole series against the exact radiation of a sphere (including
// an interior-resonance frequency), and a thin rigid spheroid against Lamb's potential-flow dipole.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "../precompute/src/bem/bem_kernels.hpp"
#include "../precompute/src/surface/surface_pieces.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/precompute/bem.hpp"
#include "fem_fixtures.hpp"
#include "test_support.hpp"

namespace chladni {
namespace {

using cd = std::complex<double>;
using precompute::BemMesh;
using precompute::BemOptions;
constexpr double kPi = std::numbers::pi;

BemMesh equilateral(double h) {  // inradius h, centroid at the origin, normal +z
  precompute::SurfaceMesh s;
  const double r = 2 * h;  // circumradius
  for (int i = 0; i < 3; ++i)
    s.vertices.push_back({r * std::cos(2 * kPi * i / 3), r * std::sin(2 * kPi * i / 3), 0});
  s.triangles = {{0, 1, 2}};
  return BemMesh(s);
}

TEST(BemQuadrature, SelfTermsOfAnEquilateralTriangleAreTheClosedForms) {
  const double h = 0.01;
  const BemMesh m = equilateral(h);
  const BemOptions o;
  const auto e = precompute::element_integrals(m, 0, {0, 0, 0}, {0, 0, 1}, 0.0, o);
  // int 1/(4 pi R) = 6 h ln(2 + sqrt 3) / (4 pi); FP int 1/(4 pi R^3) = -3 sqrt3 / (4 pi h).
  EXPECT_NEAR(e.single.real(), 6 * h * std::log(2 + std::sqrt(3.0)) / (4 * kPi), 1e-12);
  EXPECT_NEAR(e.hyper.real(), -3 * std::sqrt(3.0) / (4 * kPi * h), 1e-9 / h);
  EXPECT_EQ(e.dbl, cd(0.0));
  EXPECT_EQ(e.adjoint, cd(0.0));
}

TEST(BemQuadrature, SelfTermsAreTheLimitsFromOffTheSurface) {
  // G and the hypersingular kernel's finite part are continuous across the element's interior:
  // the closed-form self terms must equal the adaptive integrals at a point just above it.
  const double h = 0.01;
  const BemMesh m = equilateral(h);
  BemOptions o;
  o.max_depth = 16;
  o.subdivision = 0.25;
  for (double k : {0.0, 30.0, 100.0}) {
    const auto self = precompute::element_integrals(m, 0, {0, 0, 0}, {0, 0, 1}, k, o);
    const auto off = precompute::element_integrals(m, 0, {0, 0, 3e-4 * h}, {0, 0, 1}, k, o);
    // The single layer's normal derivative just above the element is -1/2 (its jump).
    EXPECT_LT(std::abs(self.single - (off.single + 0.5 * 3e-4 * h)), 1e-4 * std::abs(self.single))
        << k;
    EXPECT_LT(std::abs(self.hyper - off.hyper), 2e-3 * std::abs(self.hyper)) << k;
  }
}

TEST(BemQuadrature, NearSingularDoubleLayerIsTheSolidAngle) {
  // int dG/dn_y at k = 0 is the solid angle / 4 pi, for points close above and beside the element.
  const BemMesh m = equilateral(0.01);
  const BemOptions o;
  const Vec3 &a = m.vertices[0], &b = m.vertices[1], &c = m.vertices[2];
  for (const Vec3& x : {Vec3{0.003, 0.002, 1e-4}, Vec3{0.0, 0.0, 2e-3}, Vec3{0.02, 0.01, 5e-4},
                        Vec3{-0.011, 0.0, 3e-4}}) {
    const auto e = precompute::element_integrals(m, 0, x, {0, 0, 1}, 0.0, o);
    // Seen from the normal's side the formula's signed angle is negative; the double layer
    // (r = x - y) is positive there.
    EXPECT_NEAR(e.dbl.real(), -precompute::solid_angle(x, a, b, c) / (4 * kPi), 2e-6)
        << x[0] << " " << x[2];
  }
}

cd sphere_pressure(int l, double k, double a, double r, double cos_t) {
  const double rho0 = 1.204, c = 343.0;
  std::vector<cd> h(static_cast<std::size_t>(l) + 1);
  sph_hankel1(l, k * r, h.data());
  return cd(0, rho0 * c) * h[l] / sph_hankel1_derivative(l, k * a) *
         std::legendre(unsigned(l), cos_t);
}

// Mean of P_l(cos t) over each element (3 points), as dp/dn = i w rho0 u_n.
std::vector<cd> sphere_dpdn(const BemMesh& m, const Vec3& centre, int l, double k) {
  std::vector<cd> q(m.elements());
  const double omega = k * 343.0;
  for (std::size_t j = 0; j < q.size(); ++j) {
    const auto& t = m.triangles[j];
    double un = 0;
    for (int i = 0; i < 3; ++i) {
      Vec3 p{0, 0, 0};
      for (int c = 0; c < 3; ++c) p = add(p, scale(m.vertices[t[c]], c == i ? 2.0 / 3 : 1.0 / 6));
      const Vec3 d = sub(p, centre);
      un += std::legendre(unsigned(l), d[2] / norm(d)) / 3;
    }
    q[j] = cd(0, omega * 1.204) * un;
  }
  return q;
}

Transfer series(const BemMesh& m, double k, const Vec3& centre, std::span<const cd> p,
                std::span<const cd> q) {
  Transfer t;
  t.centre = centre;
  for (const Vec3& v : m.vertices) t.radius = std::max(t.radius, norm(sub(v, centre)));
  const int L = int(std::ceil(k * t.radius + 2 * std::cbrt(k * t.radius))) + 8;
  std::vector<cd> c = precompute::bem_multipoles(m, k, centre, L, p, q);
  std::vector<cd> h(std::size_t(L) + 1);
  sph_hankel1(L, k * t.radius, h.data());
  for (int l = 0; l <= L; ++l)
    for (int mm = -l; mm <= l; ++mm) c[sh_index(l, mm)] *= h[l];
  ModeTransfer mt;
  mt.wavenumber = k;
  mt.order = uint32_t(L);
  t.add_mode(mt, c);
  return t;
}

struct SphereCase {
  double ka;
  int level;
};

class BemSphere : public ::testing::TestWithParam<SphereCase> {};

TEST_P(BemSphere, MatchesTheExactSolutionByBemAndBySeries) {
  const double a = 0.1;
  const Vec3 centre{0.03, -0.02, 0.05};
  test::SurfaceMesh s = test::icosphere(a, GetParam().level);
  for (Vec3& v : s.vertices) v = add(v, centre);
  const BemMesh m(s);
  const double k = GetParam().ka / a;
  BemOptions o;
  precompute::BemSolver solver(m, o);
  // Directions and radii from 2a to 50a; the series about a point off the sphere's centre.
  std::vector<Vec3> pts;
  std::vector<double> rr, ct;
  for (double r : {2.0, 5.0, 20.0, 50.0}) {
    for (int d = 0; d < 7; ++d) {
      const double th = kPi * (d + 0.5) / 7, ph = 0.9 * d;
      const Vec3 u{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
      pts.push_back(add(centre, scale(u, r * a)));
      rr.push_back(r * a), ct.push_back(u[2]);
    }
  }
  const Vec3 expansion_centre = add(centre, {0.01, 0.0, -0.015});
  for (int l = 0; l <= 3; ++l) {
    const std::vector<cd> q = sphere_dpdn(m, centre, l, k);
    const auto res = solver.solve(k, q);
    EXPECT_LT(res.residual, 1e-5);
    const std::vector<cd> direct = precompute::bem_field(m, k, res.pressure, q, pts, o);
    const Transfer t = series(m, k, expansion_centre, res.pressure, q);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const cd exact = sphere_pressure(l, k, a, rr[i], ct[i]);
      if (std::abs(std::legendre(unsigned(l), ct[i])) < 0.1) continue;  // near a nodal cone
      for (const cd& got : {direct[i], t.pressure(0, pts[i])}) {
        EXPECT_LT(std::abs(std::abs(got) / std::abs(exact) - 1), 0.02)
            << "l " << l << " ka " << GetParam().ka << " r/a " << rr[i] / a;
        EXPECT_LT(std::abs(std::arg(got / exact)), 0.05)
            << "l " << l << " ka " << GetParam().ka << " r/a " << rr[i] / a;
      }
    }
  }
}

// ka = pi is the first interior Dirichlet eigenvalue (j_0(ka) = 0), where the conventional
// equation alone has no unique solution; Burton-Miller must not notice it.
INSTANTIATE_TEST_SUITE_P(Wavenumbers, BemSphere,
                         ::testing::Values(SphereCase{0.1, 3}, SphereCase{1.0, 3},
                                           SphereCase{kPi, 4}, SphereCase{6.0, 4},
                                           SphereCase{10.0, 4}));

TEST(BemThinBody, RigidOblateSpheroidRadiatesLambsDipole) {
  // Semi-axes a, a, c = a / 20, translating along its axis with velocity U at ka = 0.1. Potential
  // flow (Lamb, Hydrodynamics, Art. 114): dipole mu = V (1 + k0) U / (4 pi) with added-mass
  // coefficient k0 = g0 / (2 - g0), g0 = (2 / e^2) (1 - sqrt(1 - e^2) asin(e) / e); at small ka
  // p = w rho0 k^2 mu h_1(kr) cos t.
  const double a = 0.1, c = 0.005, U = 1e-3, k = 0.1 / a, rho0 = 1.204, c0 = 343.0;
  test::SurfaceMesh s = test::icosphere(1.0, 4);
  for (Vec3& v : s.vertices) v = {a * v[0], a * v[1], c * v[2]};
  const BemMesh m(s);
  std::vector<cd> q(m.elements());
  for (std::size_t j = 0; j < q.size(); ++j) q[j] = cd(0, k * c0 * rho0) * U * m.normal[j][2];
  const BemOptions o;
  precompute::BemSolver solver(m, o);
  const auto res = solver.solve(k, q);
  const double e = std::sqrt(1 - c * c / (a * a));
  const double g0 = 2 / (e * e) * (1 - std::sqrt(1 - e * e) * std::asin(e) / e);
  const double mu = 4.0 / 3 * kPi * a * a * c * (1 + g0 / (2 - g0)) * U / (4 * kPi);
  const double r = 20 * a;
  cd h1[2];
  sph_hankel1(1, k * r, h1);
  const cd axis = k * c0 * rho0 * k * k * mu * h1[1];
  std::vector<Vec3> pts;
  std::vector<double> cts;
  for (int d = 0; d <= 18; ++d) {
    const double th = kPi * d / 18;
    pts.push_back({r * std::sin(th), 0, r * std::cos(th)});
    cts.push_back(std::cos(th));
  }
  const std::vector<cd> p = precompute::bem_field(m, k, res.pressure, q, pts, o);
  const Transfer t = series(m, k, {0, 0, 0}, res.pressure, q);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    EXPECT_LT(std::abs(p[i] - axis * cts[i]), 0.03 * std::abs(axis)) << "angle " << i * 10;
    EXPECT_LT(std::abs(t.pressure(0, pts[i]) - axis * cts[i]), 0.03 * std::abs(axis))
        << "angle " << i * 10;
  }
}

}  // namespace
}  // namespace chladni

namespace chladni {
namespace {

TEST(BemSharpEdges, ThinBarMatchesTheFieldOfInteriorSources) {
  // A 0.3 x 0.03 x 0.01 m box (sharp edges, a 1 cm wall) whose Neumann data is that of two
  // opposite point sources inside it, 2 mm apart across the thickness (a weak, bending-like
  // radiator with a null in the bar's plane) plus a weaker monopole: the exterior field is known.
  // 3 mm elements (3968): at 6 mm the error near the null is 6 % of the peak, first order in h.
  const test::SurfaceMesh s = test::box_surface({0.3, 0.03, 0.01}, {100, 10, 4});
  const BemMesh m(s);
  const double k = 2 * kPi * 3000 / 343.0;
  const std::vector<std::pair<Vec3, cd>> src = {{{0.1, 0.015, 0.006}, 1.0},
                                                {{0.1, 0.015, 0.004}, -1.0},
                                                {{0.22, 0.012, 0.005}, cd(0.0, 0.05)}};
  auto exact = [&](const Vec3& x) {
    cd p = 0;
    for (const auto& [y, A] : src) {
      const double R = norm(sub(x, y));
      p += A * std::exp(cd(0, k * R)) / (4 * kPi * R);
    }
    return p;
  };
  std::vector<cd> q(m.elements());
  for (std::size_t j = 0; j < q.size(); ++j) {
    const auto& t = m.triangles[j];
    for (int i = 0; i < 3; ++i) {
      Vec3 x{0, 0, 0};
      for (int c = 0; c < 3; ++c) x = add(x, scale(m.vertices[t[c]], c == i ? 2.0 / 3 : 1.0 / 6));
      for (const auto& [y, A] : src) {  // dp/dn = A dG/dn_x = -A G (1 - ikR) (r.n) / R^2
        const Vec3 r = sub(x, y);
        const double R = norm(r);
        const cd g = std::exp(cd(0, k * R)) / (4 * kPi * R);
        q[j] -= A * g * cd(1, -k * R) * dot(r, m.normal[j]) / (R * R) / 3.0;
      }
    }
  }
  BemOptions o;
  precompute::BemSolver solver(m, o);
  const auto res = solver.solve(k, q);
  const Vec3 centre{0.15, 0.015, 0.005};
  std::vector<Vec3> pts;
  for (double r : {0.3, 1.0, 3.0})
    for (int d = 0; d < 12; ++d) {
      const double th = kPi * (d + 0.5) / 12, ph = 1.3 * d;
      pts.push_back(add(centre, {r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph),
                                 r * std::cos(th)}));
    }
  const std::vector<cd> direct = precompute::bem_field(m, k, res.pressure, q, pts, o);
  const Transfer t = series(m, k, centre, res.pressure, q);
  for (std::size_t i = 0; i < pts.size(); i += 12) {
    double peak = 0;  // per radius: errors relative to the largest pressure on that sphere
    for (std::size_t d = 0; d < 12; ++d) peak = std::max(peak, std::abs(exact(pts[i + d])));
    for (std::size_t d = 0; d < 12; ++d) {
      const cd ex = exact(pts[i + d]);
      EXPECT_LT(std::abs(direct[i + d] - ex), 0.03 * peak) << "point " << i + d;
      EXPECT_LT(std::abs(t.pressure(0, pts[i + d]) - ex), 0.03 * peak) << "point " << i + d;
    }
  }
}

}  // namespace
}  // namespace chladni

namespace chladni {
namespace {

// A lumpy, off-centre body (an icosphere pushed out by a smooth non-symmetric field).
BemMesh lumpy_body(int level) {
  test::SurfaceMesh s = test::icosphere(0.1, level);
  for (Vec3& v : s.vertices) {
    const double bump =
        1 + 0.25 * std::sin(14 * v[0] + 3) * std::cos(9 * v[1] - 1) + 0.15 * v[2] / 0.1;
    v = add(scale(v, bump), {0.02, -0.01, 0.03});
  }
  return BemMesh(s);
}

TEST(BemReciprocity, HoldsOnANonSymmetricBody) {
  // Two radiating solutions of the same exterior problem satisfy int (p_A q_B - p_B q_A) = 0.
  const BemMesh m = lumpy_body(3);
  const double k = 2 * kPi * 1500 / 343.0;
  std::vector<cd> qa(m.elements()), qb(m.elements());
  for (std::size_t j = 0; j < qa.size(); ++j) {
    const Vec3& c = m.centroid[j];
    qa[j] = cd(1.0 + 40 * c[0], 0.3);
    qb[j] = cd(std::cos(30 * c[1] + 20 * c[2]), -0.5 * c[0] / 0.1);
  }
  precompute::BemSolver solver(m, BemOptions{});
  const auto pa = solver.solve(k, qa).pressure, pb = solver.solve(k, qb).pressure;
  cd cross = 0;
  double scale_sum = 0;
  for (std::size_t j = 0; j < qa.size(); ++j) {
    cross += m.area[j] * (pa[j] * qb[j] - pb[j] * qa[j]);
    scale_sum += m.area[j] * std::abs(pa[j] * qb[j]);
  }
  EXPECT_LT(std::abs(cross), 0.01 * scale_sum);
}

TEST(BemSolver, SeveralRightHandSidesMatchSeparateSolves) {
  // One assembly and at most one factorization for modes sharing a wavenumber: the direct, the
  // dense GMRES and the hierarchical paths give each right-hand side its own solution.
  const BemMesh m = lumpy_body(2);  // 320 elements
  const double k = 2 * kPi * 1500 / 343.0;
  std::vector<std::vector<cd>> qs(3, std::vector<cd>(m.elements()));
  for (std::size_t j = 0; j < m.elements(); ++j) {
    const Vec3& c = m.centroid[j];
    qs[0][j] = cd(1.0 + 40 * c[0], 0.3);
    qs[1][j] = cd(std::cos(30 * c[1] + 20 * c[2]), -0.5 * c[0] / 0.1);
    qs[2][j] = 0;  // a silent mode stays silent
  }
  BemOptions direct, iterative, hierarchical;
  iterative.direct_limit = 100;
  hierarchical.hmatrix_limit = 200;
  for (const BemOptions& o : {direct, iterative, hierarchical}) {
    precompute::BemSolver together(m, o);
    const auto batch = together.solve(k, std::span<const std::vector<cd>>(qs));
    ASSERT_EQ(batch.size(), qs.size());
    EXPECT_TRUE(batch[0].factorized);
    EXPECT_FALSE(batch[1].factorized) << "the second right-hand side reuses the factors";
    for (std::size_t v = 0; v < qs.size(); ++v) {
      precompute::BemSolver alone(m, o);
      const auto want = alone.solve(k, qs[v]);
      double diff = 0, size = 0;
      for (std::size_t j = 0; j < m.elements(); ++j) {
        diff += std::norm(batch[v].pressure[j] - want.pressure[j]);
        size += std::norm(want.pressure[j]);
      }
      if (v == 2) {
        EXPECT_EQ(diff, 0.0);
      } else {
        EXPECT_LT(std::sqrt(diff / size), o.direct_limit > m.elements() ? 1e-12 : 1e-4)
            << "right-hand side " << v << ", direct limit " << o.direct_limit;
      }
    }
  }
}

TEST(BemHMatrix, AgreesWithTheDenseSolveAtNearbyFrequencies) {
  // The same system stored densely and as a hierarchical matrix (far blocks compressed to 1e-4,
  // GMRES preconditioned by its LU at 1e-2, reused at the next frequency), at kR ~ 9, on a lumpy
  // body and on a thin spheroid (c/a = 0.05), whose near blocks hold the opposite face.
  test::SurfaceMesh thin = test::icosphere(1.0, 3);
  for (Vec3& v : thin.vertices) v = {0.1 * v[0], 0.1 * v[1], 0.005 * v[2]};
  for (const BemMesh& m : {lumpy_body(3), BemMesh(thin)}) {
    BemOptions hierarchical;
    hierarchical.hmatrix_limit = 400;
    precompute::BemSolver dense(m, BemOptions{}), compressed(m, hierarchical);
    const double k0 = 2 * kPi * 4000 / 343.0;
    for (double k : {k0, 1.01 * k0}) {
      std::vector<cd> q(m.elements());
      for (std::size_t j = 0; j < q.size(); ++j) {
        const Vec3& c = m.centroid[j];
        q[j] = cd(std::cos(30 * c[1] + 20 * c[2]), 1.0 - 40 * c[0]);
      }
      const auto want = dense.solve(k, q);
      const auto got = compressed.solve(k, q);
      EXPECT_LT(got.residual, 1e-5);
      EXPECT_EQ(got.factorized, k == k0) << "the LU of k0 preconditions the next frequency";
      EXPECT_GE(got.iterations, 1);
      double diff = 0, size = 0;
      for (std::size_t j = 0; j < q.size(); ++j) {
        diff += std::norm(got.pressure[j] - want.pressure[j]);
        size += std::norm(want.pressure[j]);
      }
      EXPECT_LT(std::sqrt(diff / size), 1e-3) << "k " << k;
    }
  }
}

}  // namespace
}  // namespace chladni

namespace chladni {
namespace {

TEST(BemGpu, RowsMatchTheDoubleReferenceAndSolvesAgree) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  test::SurfaceMesh s = test::icosphere(0.1, 3);
  for (Vec3& v : s.vertices) v = {v[0] * 1.3, v[1], v[2] * 0.7};  // an ellipsoid
  const BemMesh m(s);
  const std::size_t n = m.elements();
  std::vector<cd> q(n);
  for (std::size_t j = 0; j < n; ++j) q[j] = cd(m.normal[j][2], 0.3 * m.normal[j][0]);
  const precompute::bem_detail::FarGeometry g(m);
  precompute::BemGpuRows gpu(ctx, m);
  for (double f : {200.0, 3000.0, 12000.0}) {  // kR from 0.4 to 29
    const double k = 2 * kPi * f / 343.0, al = 0.01;
    std::vector<std::complex<float>> entries, rhs;
    const std::size_t rows = std::min<std::size_t>(gpu.block_rows(), 300), row0 = 500;
    gpu.rows(k, al, q, row0, rows, entries, rhs);
    std::vector<double> rre(n), rim(n), tre(n), tim(n);
    double worst_entry = 0, worst_rhs = 0;
    for (std::size_t r = 0; r < rows; ++r) {
      const std::size_t i = row0 + r;
      precompute::bem_detail::far_row(g, m.centroid[i], m.normal[i], k, al, rre.data(), rim.data(),
                                      tre.data(), tim.data());
      double num = 0, den = 0;
      cd sum = 0;
      double mag = 0;
      for (std::size_t j = 0; j < n; ++j) {
        if (j == i) continue;
        const cd ref(rre[j], rim[j]);
        num += std::norm(cd(entries[r * n + j]) - ref), den += std::norm(ref);
        sum += cd(tre[j], tim[j]) * q[j], mag += std::abs(cd(tre[j], tim[j]) * q[j]);
      }
      worst_entry = std::max(worst_entry, std::sqrt(num / den));
      worst_rhs = std::max(worst_rhs, std::abs(cd(rhs[r]) - sum) / mag);
    }
    EXPECT_LT(worst_entry, 1e-5) << f << " Hz";
    EXPECT_LT(worst_rhs, 1e-5) << f << " Hz";
    // The whole solve with the device rows agrees with the CPU's.
    BemOptions cpu_o, gpu_o;
    gpu_o.gpu = ctx;
    precompute::BemSolver cpu_s(m, cpu_o), gpu_s(m, gpu_o);
    // Two right-hand sides at once: the device sums the first, the CPU the second.
    std::vector<std::vector<cd>> qs = {q, q};
    for (std::size_t j = 0; j < n; ++j) qs[1][j] = cd(1.0 - 20 * m.centroid[j][1], 0.2);
    const auto both = gpu_s.solve(k, std::span<const std::vector<cd>>(qs));
    for (std::size_t v = 0; v < qs.size(); ++v) {
      const auto pc = cpu_s.solve(k, qs[v]).pressure;
      const auto& pg = both[v].pressure;
      double num = 0, den = 0;
      for (std::size_t j = 0; j < n; ++j) num += std::norm(pg[j] - pc[j]), den += std::norm(pc[j]);
      EXPECT_LT(std::sqrt(num / den), 1e-4) << f << " Hz, right-hand side " << v;
    }
  }
  EXPECT_EQ(ctx->validation_errors(), 0u);
}

}  // namespace
}  // namespace chladni
