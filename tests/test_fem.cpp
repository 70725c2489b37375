// FEM element matrices against hand-derived values, the patch test, rigid-body null space and
// lumped mass.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "chladni/core/error.hpp"
#include "chladni/precompute/fem.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

Material steel() {
  return find_material("steel");
}

// A 2 x 2 x 2 block of cubes, each split into six tets around its main diagonal (Kuhn), with the
// middle node (1,1,1) interior, the corners jittered so that no element is special.
TetMesh block_mesh(double jitter = 0.07) {
  TetMesh m;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  auto id = [](int i, int j, int k) { return uint32_t(i + 3 * j + 9 * k); };
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const bool inner = i == 1 && j == 1 && k == 1;
        m.nodes.push_back({0.1 * (i + (inner ? u(rng) : 0)), 0.1 * (j + (inner ? u(rng) : 0)),
                           0.1 * (k + (inner ? u(rng) : 0))});
      }
  constexpr int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          std::array<uint32_t, 4> t;
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            t[s + 1] = id(c[0], c[1], c[2]);
          }
          const Vec3 &a = m.nodes[t[0]], &b = m.nodes[t[1]], &cc = m.nodes[t[2]],
                     &d = m.nodes[t[3]];
          const Eigen::Vector3d e1(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
          const Eigen::Vector3d e2(cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]);
          const Eigen::Vector3d e3(d[0] - a[0], d[1] - a[1], d[2] - a[2]);
          if (e1.cross(e2).dot(e3) < 0) std::swap(t[2], t[3]);
          m.tets.push_back(t);
        }
  m.surface_vertices = 0;
  return m;
}

Eigen::MatrixXd dense(const SparseMatrix& A) {
  return Eigen::MatrixXd(A);
}

}  // namespace

TEST(FemElement, LinearTetMatchesHandDerivedEntries) {
  // Unit corner tet: grad N0 = (-1,-1,-1), grad N1..3 = e_x, e_y, e_z, V = 1/6.
  const Vec3 x[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const double lambda = 3.0, mu = 2.0, rho = 5.0;
  Mat12 K, M;
  p1_element(x, lambda, mu, rho, K, M);
  // K_(a,i),(b,j) = V (lambda g_ai g_bj + mu g_aj g_bi + mu delta_ij g_a.g_b)
  EXPECT_NEAR(K(3, 3), (lambda + 2 * mu) / 6, 1e-12);   // node 1 x, node 1 x
  EXPECT_NEAR(K(4, 4), mu / 6, 1e-12);                  // node 1 y, node 1 y
  EXPECT_NEAR(K(3, 7), lambda / 6, 1e-12);              // node 1 x, node 2 y
  EXPECT_NEAR(K(4, 6), mu / 6, 1e-12);                  // node 1 y, node 2 x
  EXPECT_NEAR(K(0, 0), (lambda + 4 * mu) / 6, 1e-12);   // node 0 x: |g0|^2 = 3
  EXPECT_NEAR(K(0, 3), -(lambda + 2 * mu) / 6, 1e-12);  // node 0 x, node 1 x
  EXPECT_NEAR(K(3, 6), 0.0, 1e-12);                     // node 1 x, node 2 x: g1.g2 = 0
  // Consistent mass: rho V / 10 on the diagonal, rho V / 20 between nodes, none across axes.
  EXPECT_NEAR(M(0, 0), rho / 60, 1e-12);
  EXPECT_NEAR(M(0, 3), rho / 120, 1e-12);
  EXPECT_NEAR(M(0, 4), 0.0, 1e-15);
  EXPECT_NEAR(M.sum(), 3 * rho / 6, 1e-12);  // mass times three axes
  EXPECT_LT((K - K.transpose()).norm(), 1e-12);
}

TEST(FemElement, QuadraticTetMassHasTheClassicStructure) {
  const Vec3 x[4] = {{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 0, 3}};  // V = 1
  Mat30 K, M;
  p2_element(x, 1.0, 1.0, 1.0, K, M);
  // rho V / 420 x [corner 6, corner-corner 1, corner-own-edge -4, corner-far-edge -6,
  // edge 32, edges sharing a corner 16, opposite edges 8]; node order corners, 01 12 02 03 13 23.
  EXPECT_NEAR(M(0, 0) * 420, 6, 1e-9);
  EXPECT_NEAR(M(0, 3) * 420, 1, 1e-9);
  EXPECT_NEAR(M(0, 12) * 420, -4, 1e-9);  // corner 0, edge 01
  EXPECT_NEAR(M(0, 15) * 420, -6, 1e-9);  // corner 0, edge 12
  EXPECT_NEAR(M(12, 12) * 420, 32, 1e-9);
  EXPECT_NEAR(M(12, 15) * 420, 16, 1e-9);  // edges 01 and 12 share corner 1
  EXPECT_NEAR(M(12, 27) * 420, 8, 1e-9);   // edges 01 and 23 are opposite
  EXPECT_NEAR(M.sum(), 3.0, 1e-9);         // total mass 1 on each axis
  EXPECT_LT((K - K.transpose()).norm(), 1e-9 * K.norm());
}

TEST(FemElement, InvertedTetIsReported) {
  const Vec3 x[4] = {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}};
  Mat12 K, M;
  EXPECT_THROW(p1_element(x, 1, 1, 1, K, M), InputError);
}

class FemOrder : public ::testing::TestWithParam<int> {};

TEST_P(FemOrder, RigidBodyMotionsAreTheNullSpaceOfK) {
  const FemMesh fem = make_fem_mesh(block_mesh(), GetParam());
  const FemMatrices km = assemble(fem, steel(), MassKind::Consistent, 2);
  const Eigen::MatrixXd R = rigid_body_modes(fem.nodes);
  const double scale = dense(km.K).norm();
  for (int c = 0; c < 6; ++c)
    EXPECT_LT((km.K * R.col(c)).norm() / (scale * R.col(c).norm()), 1e-13) << "motion " << c;
  // Exactly six zero eigenvalues: the seventh is far from zero.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense(km.K));
  const auto ev = es.eigenvalues();
  EXPECT_LT(std::abs(ev(5)), 1e-10 * ev(ev.size() - 1));
  EXPECT_GT(ev(6), 1e-6 * ev(ev.size() - 1));
  // Mass: total mass rho V on each axis, and M is positive definite.
  const Eigen::VectorXd ones_x = R.col(0);
  EXPECT_NEAR(ones_x.dot(km.M * ones_x), 7850 * 0.008, 1e-9);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(dense(km.M)).eigenvalues()(0), 0);
}

TEST_P(FemOrder, PatchTestReproducesConstantStrainExactly) {
  // u = A x + b: every interior node is in equilibrium and the strain energy is V W(eps).
  const FemMesh fem = make_fem_mesh(block_mesh(), GetParam());
  const Material mat = steel();
  const FemMatrices km = assemble(fem, mat, MassKind::Consistent, 1);
  Eigen::Matrix3d A;
  A << 1e-3, 2e-4, -3e-4, 5e-4, -2e-3, 1e-4, 0, 7e-4, 4e-4;
  Eigen::VectorXd u(fem.dofs());
  for (std::size_t n = 0; n < fem.nodes.size(); ++n) {
    const Eigen::Vector3d x(fem.nodes[n][0], fem.nodes[n][1], fem.nodes[n][2]);
    u.segment<3>(3 * n) = A * x + Eigen::Vector3d(1e-3, -2e-3, 5e-4);
  }
  const Eigen::VectorXd f = km.K * u;
  const double fscale = f.cwiseAbs().maxCoeff();
  for (std::size_t n = 0; n < fem.nodes.size(); ++n) {
    const Vec3& p = fem.nodes[n];
    const bool interior = p[0] > 1e-9 && p[0] < 0.2 - 1e-9 && p[1] > 1e-9 && p[1] < 0.2 - 1e-9 &&
                          p[2] > 1e-9 && p[2] < 0.2 - 1e-9;
    if (interior) {
      EXPECT_LT(f.segment<3>(3 * n).norm(), 1e-10 * fscale) << "node " << n;
    }
  }
  const Eigen::Matrix3d eps = 0.5 * (A + A.transpose());
  const double W = 0.5 * mat.lame_lambda() * eps.trace() * eps.trace() +
                   mat.lame_mu() * (eps.array() * eps.array()).sum();
  EXPECT_NEAR(0.5 * u.dot(f), 0.008 * W, 1e-9 * 0.008 * W);
}

TEST_P(FemOrder, LumpedMassIsDiagonalPositiveAndKeepsTheTotal) {
  const FemMesh fem = make_fem_mesh(block_mesh(), GetParam());
  const FemMatrices km = assemble(fem, steel(), MassKind::Lumped, 2);
  const Eigen::MatrixXd M = dense(km.M);
  EXPECT_NEAR(M.sum(), 3 * 7850 * 0.008, 1e-9);
  EXPECT_NEAR((M - Eigen::MatrixXd(M.diagonal().asDiagonal())).norm(), 0, 1e-15);
  EXPECT_GT(M.diagonal().minCoeff(), 0);
}

// M stores only the entries that can be nonzero (one direction with itself: a third of K's),
// and is still the sum of the element mass matrices, which the factorization and the mass
// products rely on.
TEST_P(FemOrder, MassStoresAThirdOfTheEntriesAndEqualsTheElementSum) {
  const FemMesh fem = make_fem_mesh(block_mesh(), GetParam());
  const Material mat = steel();
  const FemMatrices km = assemble(fem, mat, MassKind::Consistent, 2);
  EXPECT_EQ(3 * km.M.nonZeros(), km.K.nonZeros());
  const int npe = fem.nodes_per_element();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(Eigen::Index(fem.dofs()), Eigen::Index(fem.dofs()));
  for (std::size_t e = 0; e < fem.element_count(); ++e) {
    const uint32_t* en = &fem.elements[e * std::size_t(npe)];
    const Vec3 x[4] = {fem.nodes[en[0]], fem.nodes[en[1]], fem.nodes[en[2]], fem.nodes[en[3]]};
    Eigen::MatrixXd Me;
    if (npe == 4) {
      Mat12 K1, M1;
      p1_element(x, mat.lame_lambda(), mat.lame_mu(), mat.density, K1, M1);
      Me = M1;
    } else {
      Mat30 K2, M2;
      p2_element(x, mat.lame_lambda(), mat.lame_mu(), mat.density, K2, M2);
      Me = M2;
    }
    for (int a = 0; a < npe; ++a)
      for (int b = 0; b < npe; ++b)
        M.block<3, 3>(3 * en[a], 3 * en[b]) += Me.block<3, 3>(3 * a, 3 * b);
  }
  EXPECT_LT((dense(km.M) - M).cwiseAbs().maxCoeff(), 1e-12 * M.cwiseAbs().maxCoeff());
  const FemMatrices lumped = assemble(fem, mat, MassKind::Lumped, 2);
  EXPECT_EQ(lumped.M.nonZeros(), lumped.M.rows());
}

TEST_P(FemOrder, AssemblyIsDeterministicAndThreadCountOnlyReordersSums) {
  const FemMesh fem = make_fem_mesh(block_mesh(), GetParam());
  const FemMatrices a = assemble(fem, steel(), MassKind::Consistent, 3);
  const FemMatrices b = assemble(fem, steel(), MassKind::Consistent, 3);
  const FemMatrices c = assemble(fem, steel(), MassKind::Consistent, 1);
  EXPECT_EQ((dense(a.K) - dense(b.K)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((dense(a.M) - dense(b.M)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT((dense(a.K) - dense(c.K)).cwiseAbs().maxCoeff(),
            1e-12 * dense(a.K).cwiseAbs().maxCoeff());
  EXPECT_LT((dense(a.M) - dense(c.M)).cwiseAbs().maxCoeff(),
            1e-12 * dense(a.M).cwiseAbs().maxCoeff());
}

INSTANTIATE_TEST_SUITE_P(Orders, FemOrder, ::testing::Values(1, 2));

TEST(FemMaterial, InvalidMaterialsAreRefusedByName) {
  Material m = steel();
  m.poisson_ratio = 0.5;
  EXPECT_THROW(m.validate(), InputError);
  m = steel();
  m.youngs_modulus = std::nan("");
  try {
    m.validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Young's modulus"), std::string::npos);
  }
  m = steel();
  m.density = -1;
  EXPECT_THROW(m.validate(), InputError);
  EXPECT_THROW(find_material("unobtainium"), InputError);
}

TEST(FemMaterial, PresetsIncludeSterlingLinTable) {
  const Material p = find_material("sl2016-porcelain");
  EXPECT_DOUBLE_EQ(p.youngs_modulus, 20e9);
  EXPECT_EQ(p.damping.kind, DampingModel::Kind::Rayleigh);
  EXPECT_DOUBLE_EQ(p.damping.alpha[0], 189);
  EXPECT_DOUBLE_EQ(p.damping.alpha[1], 1.5e-8);
  const Material c = find_material("sl2016-plastic2:caughey");
  ASSERT_EQ(c.damping.alpha.size(), 3u);
  EXPECT_DOUBLE_EQ(c.damping.alpha[2], 5.6e-14);
  EXPECT_DOUBLE_EQ(find_material("sl2016-aluminum:power").damping.alpha[1], 0.445);
  for (const char* name : {"steel", "aluminium", "brass", "glass", "porcelain", "ceramic", "oak",
                           "pine", "acrylic", "abs", "rubber"}) {
    const Material m = find_material(name);
    EXPECT_FALSE(m.source.empty()) << name;
    // Every preset damps audible modes underdamped: c(2 pi 1 kHz) < 2 omega.
    const double w = 2 * M_PI * 1000;
    EXPECT_LT(m.damping.coefficient(w), 2 * w) << name;
  }
}
