// The whole precompute pipeline against analytic elasticity: a free-free bar against Timoshenko
// beam theory and a free solid sphere against Lamb's solution, at the default settings.
#include <gtest/gtest.h>

#include <map>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/precompute/precompute.hpp"
#include "elastic_reference.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

const std::string kMeshes = CHLADNI_SHARED_MESHES;

double hz(double omega) {
  return omega / (2 * std::numbers::pi);
}

// Unit icosahedron subdivided `level` times and projected onto the sphere of radius r.
SurfaceMesh icosphere(double r, int level) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  SurfaceMesh m;
  m.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto [it, fresh] = mid.emplace(std::minmax(a, b), uint32_t(m.vertices.size()));
      if (fresh) {
        const Vec3 &p = m.vertices[a], &q = m.vertices[b];
        m.vertices.push_back({(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2});
      }
      return it->second;
    };
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& f : m.triangles) {
      const uint32_t a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c}), next.push_back({f[1], b, a}), next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  for (Vec3& v : m.vertices) {
    const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (double& x : v) x *= r / l;
  }
  return m;
}

enum class Kind { BendZ, BendY, Other };

// Bar modes by shape: mostly across z (thickness) or y (width), and bending (the transverse
// motion is mirror-symmetric across the section) rather than torsion (antisymmetric).
std::vector<Kind> classify(const Soundbank& b) {
  const std::size_t nv = b.vertices.size();
  Vec3 c{0, 0, 0};
  for (const Vec3& v : b.vertices)
    for (int k = 0; k < 3; ++k) c[k] += v[k] / double(nv);
  // mirror[axis][v]: the vertex nearest to v reflected across the centre plane normal to axis.
  std::vector<std::size_t> mirror[3];
  for (int axis : {1, 2}) {
    for (std::size_t v = 0; v < nv; ++v) {
      Vec3 p = b.vertices[v];
      p[axis] = 2 * c[axis] - p[axis];
      std::size_t best = 0;
      double best_d = INFINITY;
      for (std::size_t w = 0; w < nv; ++w) {
        const double dx = b.vertices[w][0] - p[0], dy = b.vertices[w][1] - p[1],
                     dz = b.vertices[w][2] - p[2];
        const double d = dx * dx + dy * dy + dz * dz;
        if (d < best_d) best_d = d, best = w;
      }
      mirror[axis].push_back(best);
    }
  }
  std::vector<Kind> out;
  for (std::size_t i = 0; i < b.mode_count(); ++i) {
    auto s = [&](std::size_t v, int k) { return double(b.shapes[(i * nv + v) * 3 + k]); };
    double e[3] = {0, 0, 0}, sym_z = 0, sym_y = 0;
    for (std::size_t v = 0; v < nv; ++v) {
      for (int k = 0; k < 3; ++k) e[k] += s(v, k) * s(v, k);
      sym_z += s(v, 2) * s(mirror[1][v], 2);  // z motion mirrored across the width
      sym_y += s(v, 1) * s(mirror[2][v], 1);  // y motion mirrored across the thickness
    }
    const double total = e[0] + e[1] + e[2];
    if (e[2] > 0.6 * total && sym_z > 0.5 * e[2])
      out.push_back(Kind::BendZ);
    else if (e[1] > 0.6 * total && sym_y > 0.5 * e[1])
      out.push_back(Kind::BendY);
    else
      out.push_back(Kind::Other);
  }
  return out;
}

}  // namespace

TEST(ModalFem, SteelBarMatchesTimoshenkoWithinOnePercent) {
  PrecomputeOptions o;  // defaults: steel, quadratic tets, all modes below 20 kHz
  PrecomputeReport r;
  const Soundbank b = precompute_mesh(kMeshes + "/bar.obj", o, r);
  EXPECT_EQ(r.eigen.rigid_removed, 6u);
  EXPECT_LT(r.max_residual, 1e-6);
  ASSERT_GT(b.mode_count(), 8u);
  EXPECT_GT(hz(b.omega[0]), 500.0);  // the first kept mode is elastic, not rigid

  const double L = 0.3, w = 0.03, h = 0.01, E = 200e9, nu = 0.29, rho = 7850;
  const double kappa = test::cowper_rectangle(nu);
  const auto ref_z = test::timoshenko_free_free(L, E, nu, rho, w * h, w * h * h * h / 12, kappa, 4);
  const auto ref_y = test::timoshenko_free_free(L, E, nu, rho, w * h, h * w * w * w / 12, kappa, 2);
  const auto kinds = classify(b);
  std::vector<double> fz, fy;
  for (std::size_t i = 0; i < b.mode_count(); ++i) {
    const double wd = std::sqrt(b.omega[i] * b.omega[i] - b.decay[i] * b.decay[i]);
    if (kinds[i] == Kind::BendZ) fz.push_back(hz(wd));
    if (kinds[i] == Kind::BendY) fy.push_back(hz(wd));
  }
  ASSERT_GE(fz.size(), ref_z.size());
  ASSERT_GE(fy.size(), ref_y.size());
  for (std::size_t k = 0; k < ref_z.size(); ++k)
    EXPECT_NEAR(fz[k] / ref_z[k], 1.0, 0.01) << "bending across thickness " << k + 1 << ": "
                                             << fz[k] << " Hz vs Timoshenko " << ref_z[k];
  for (std::size_t k = 0; k < ref_y.size(); ++k)
    EXPECT_NEAR(fy[k] / ref_y[k], 1.0, 0.01)
        << "bending across width " << k + 1 << ": " << fy[k] << " Hz vs Timoshenko " << ref_y[k];
}

TEST(ModalFem, FreeSphereMatchesLambWithinOnePercent) {
  // Steel sphere of radius 0.1 m: the n = 2 torsional and spheroidal modes lie near 12.5 and
  // 13.2 kHz, each five-fold degenerate; --max-freq 15 kHz sizes the mesh for them.
  const double a = 0.1;
  PrecomputeOptions o;
  o.max_frequency = 15000;
  PrecomputeReport r;
  const Soundbank b = precompute_surface(icosphere(a, 3), "icosphere", o, r);
  EXPECT_EQ(r.eigen.rigid_removed, 6u);
  const double cs = o.material.shear_speed(), nu = o.material.poisson_ratio;
  const double f_t2 = test::lamb_torsional(2, 4)[0] * cs / (2 * std::numbers::pi * a);
  const double f_s2 = test::lamb_spheroidal(2, nu, 4)[0] * cs / (2 * std::numbers::pi * a);
  for (const auto& [name, ref] :
       {std::pair<const char*, double>{"torsional n=2", f_t2}, {"spheroidal n=2", f_s2}}) {
    int near = 0;
    for (double w : b.omega) near += std::abs(hz(w) / ref - 1) < 0.01;
    EXPECT_EQ(near, 5) << name << " at " << ref << " Hz";
  }
  EXPECT_NEAR(hz(b.omega[0]) / f_t2, 1.0, 0.01);  // the gravest mode is torsional
}

TEST(ModalFem, FirstNModesAndBandLimitsAreHonoured) {
  PrecomputeOptions o;
  o.max_modes = 5;
  o.max_tet_volume = 1e-6;
  PrecomputeReport r;
  const Soundbank b = precompute_mesh(kMeshes + "/bar.obj", o, r);
  EXPECT_EQ(r.computed, 5u);
  EXPECT_EQ(b.mode_count(), 5u);
  for (std::size_t i = 1; i < b.mode_count(); ++i) EXPECT_GE(b.omega[i], b.omega[i - 1]);
  // Mass normalization survives to the bank: the shapes are those of v^T M v = 1 vectors, so
  // the largest surface displacement of a 0.7 kg bar's bending mode is about 2 / sqrt(m).
  float peak = 0;
  for (std::size_t v = 0; v < b.vertices.size(); ++v)
    peak = std::max(peak, std::abs(b.shapes[v * 3 + 2]));
  EXPECT_NEAR(peak * std::sqrt(7850 * 9e-5), 2.0, 0.3);

  // A sample rate of 2 kHz leaves only the modes below 1 kHz.
  o.sample_rate = 2000;
  PrecomputeReport r2;
  const Soundbank b2 = precompute_mesh(kMeshes + "/bar.obj", o, r2);
  EXPECT_EQ(b2.mode_count(), 1u);
  EXPECT_EQ(r2.above_band, 4u);
}

TEST(ModalFem, DampingPresetsSetDecayRates) {
  PrecomputeOptions o;
  o.material = find_material("sl2016-porcelain");
  o.max_modes = 3;
  o.order = 1;
  o.max_tet_volume = 1e-6;
  PrecomputeReport r;
  const Soundbank b = precompute_mesh(kMeshes + "/bar.obj", o, r);
  for (std::size_t i = 0; i < b.mode_count(); ++i)  // d = (a1 + a2 omega^2) / 2
    EXPECT_NEAR(b.decay[i], 0.5 * (189 + 1.5e-8 * b.omega[i] * b.omega[i]), 1e-9 * b.decay[i]);
  EXPECT_EQ(b.material.name, "sl2016-porcelain");
}

TEST(ModalFem, ObjectWithoutAudibleModesIsRefused) {
  PrecomputeOptions o;
  o.max_frequency = 300;  // the bar's first mode is at 575 Hz
  o.order = 1;
  o.max_tet_volume = 1e-6;
  PrecomputeReport r;
  try {
    precompute_mesh(kMeshes + "/bar.obj", o, r);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no mode lies in"), std::string::npos) << e.what();
  }
}
