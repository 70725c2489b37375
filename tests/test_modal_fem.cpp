// The whole precompute pipeline against analytic elasticity: a free-free bar against Timoshenko
// beam theory and a free solid sphere against Lamb's solution, at the default settings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <numeric>

#include "../precompute/src/eigen/cholmod_factor.hpp"
#include "../precompute/src/eigen/symmetric_product.hpp"
#include "chladni/core/error.hpp"
#include "chladni/precompute.hpp"
#include "chladni/precompute/eigensolve.hpp"
#include "chladni/precompute/fem.hpp"
#include "chladni/precompute/tet_mesh.hpp"
#include "elastic_reference.hpp"
#include "fem_fixtures.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

using chladni::test::kMeshes;

double hz(double omega) {
  return omega / (2 * std::numbers::pi);
}

// A steel box's P2 mesh within max_volume, and its matrices.
std::pair<FemMesh, FemMatrices> steel_box(double max_volume) {
  TetOptions t;
  t.max_volume = max_volume;
  const TetMesh tets = tetrahedralize(test::box_surface({0.3, 0.18, 0.12}, {4, 2, 2}), t);
  FemMesh fem = make_fem_mesh(tets, 2);
  FemMatrices km = assemble(fem, find_material("steel"), MassKind::Consistent);
  return {std::move(fem), std::move(km)};
}

}  // namespace

TEST(ModalFem, SteelBarMatchesTimoshenkoWithinOnePercent) {
  PrecomputeOptions o;  // defaults: steel, quadratic tets, all modes below 20 kHz
  o.transfer = false;   // frequencies only (transfer has its own tests)
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
  const auto kinds = test::classify_bar_modes(b);
  std::vector<double> fz, fy;
  for (std::size_t i = 0; i < b.mode_count(); ++i) {
    const double wd = std::sqrt(b.omega[i] * b.omega[i] - b.decay[i] * b.decay[i]);
    if (kinds[i] == test::BarMode::BendZ) fz.push_back(hz(wd));
    if (kinds[i] == test::BarMode::BendY) fy.push_back(hz(wd));
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
  o.transfer = false;
  PrecomputeReport r;
  const Soundbank b = precompute_surface(test::icosphere(a, 3), "icosphere", o, r);
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

// A 1 m steel sphere asked for its first 10 modes at otherwise default settings: sized from
// --max-freq (20 kHz) it would need billions of tetrahedra; meshed from the modes asked for
// (the coarsest quality mesh, refined while the error estimate asks) the modes (the n = 2
// torsional and spheroidal quintuplets) land within 1 % of Lamb's solution.
TEST(ModalFem, MaxModesMeshesForTheModesAskedFor) {
  const double a = 1.0;
  PrecomputeOptions o;
  o.max_modes = 10;
  o.transfer = false;
  PrecomputeReport r;
  const Soundbank b = precompute_surface(test::icosphere(a, 3), "icosphere", o, r);
  ASSERT_EQ(b.mode_count(), 10u);
  const double cs = o.material.shear_speed(), nu = o.material.poisson_ratio;
  const double f_t2 = test::lamb_torsional(2, 4)[0] * cs / (2 * std::numbers::pi * a);
  const double f_s2 = test::lamb_spheroidal(2, nu, 4)[0] * cs / (2 * std::numbers::pi * a);
  EXPECT_TRUE(r.converged) << r.unconverged_reason;
  ASSERT_FALSE(r.passes.empty());
  EXPECT_LE(r.passes.back().worst_error, o.tolerance);
  EXPECT_TRUE(std::any_of(r.stages.begin(), r.stages.end(),
                          [](const StageTime& s) { return s.name == "error estimate"; }));
  EXPECT_LT(r.tets, 200000u);
  for (const auto& [name, ref] :
       {std::pair<const char*, double>{"torsional n=2", f_t2}, {"spheroidal n=2", f_s2}}) {
    int near = 0;
    for (double w : b.omega) near += std::abs(hz(w) / ref - 1) < 0.01;
    EXPECT_EQ(near, 5) << name << " at " << ref << " Hz";
  }
  EXPECT_NE(b.metadata_json.find("frequency_error_estimate"), std::string::npos);
  // The estimate bounds each mode's discretization error: against a solve with tets an eighth
  // the size on the same (faceted) surface. (The faceting itself, 0.3 % here, is the surface's,
  // not the elements'.)
  ASSERT_EQ(r.frequency_error.size(), 10u);
  PrecomputeOptions fine = o;
  fine.max_tet_volume = r.max_tet_volume / 8;
  PrecomputeReport rf;
  const Soundbank bf = precompute_surface(test::icosphere(a, 3), "icosphere", fine, rf);
  ASSERT_EQ(bf.mode_count(), 10u);
  for (std::size_t i = 0; i < 10; ++i) {
    const double err = std::abs(b.omega[i] / bf.omega[i] - 1);
    EXPECT_LE(err, r.frequency_error[i] + 2e-4) << "mode " << i;
    EXPECT_LE(r.frequency_error[i], o.tolerance) << "mode " << i;
    EXPECT_LT(rf.frequency_error[i], r.frequency_error[i]) << "mode " << i;  // finer: smaller
  }
}

TEST(ModalFem, FirstNModesAndBandLimitsAreHonoured) {
  PrecomputeOptions o;
  o.max_modes = 5;
  o.max_tet_volume = 1e-6;
  o.transfer = false;
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

  // --max-freq 1000 leaves only the first mode, and the solve stops there rather than find the
  // other four; a sample rate of 8 kHz drops what lies above 4 kHz (574, 1574, 1671, 2964,
  // 3061 Hz kept; 4355, 5004, 5954 Hz dropped).
  o.max_frequency = 1000;
  PrecomputeReport r2;
  const Soundbank b2 = precompute_mesh(kMeshes + "/bar.obj", o, r2);
  EXPECT_EQ(b2.mode_count(), 1u);
  EXPECT_EQ(r2.computed, 1u);
  EXPECT_EQ(r2.above_band, 0u);
  o.max_frequency = 20000;
  o.max_modes = 8;
  o.sample_rate = 8000;
  PrecomputeReport r3;
  const Soundbank b3 = precompute_mesh(kMeshes + "/bar.obj", o, r3);
  EXPECT_EQ(b3.mode_count(), 5u);
  EXPECT_EQ(r3.above_band, 3u);
}

TEST(ModalFem, DampingPresetsSetDecayRates) {
  PrecomputeOptions o;
  o.material = find_material("sl2016-porcelain");
  o.max_modes = 3;
  o.order = 1;
  o.max_tet_volume = 1e-6;
  o.transfer = false;
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

TEST(ModalFem, BlockLanczosAndSpectraAgree) {
  PrecomputeOptions o;
  o.max_modes = 12;
  o.max_tet_volume = 1e-6;
  o.transfer = false;
  PrecomputeReport rb, rs;
  const Soundbank b = precompute_mesh(kMeshes + "/bar.obj", o, rb);
  o.eigensolver = EigenOptions::Method::Spectra;
  const Soundbank s = precompute_mesh(kMeshes + "/bar.obj", o, rs);
  ASSERT_EQ(b.mode_count(), s.mode_count());
  for (std::size_t i = 0; i < b.mode_count(); ++i) {
    EXPECT_NEAR(b.omega[i] / s.omega[i], 1.0, 1e-9) << "mode " << i;
    EXPECT_LT(b.residual[i], 1e-6);
    // Same shape up to sign (modes here are not degenerate).
    const std::size_t nv = b.vertices.size();
    double dot = 0, nb = 0, ns = 0;
    for (std::size_t k = 0; k < 3 * nv; ++k) {
      const double x = b.shapes[i * 3 * nv + k], y = s.shapes[i * 3 * nv + k];
      dot += x * y, nb += x * x, ns += y * y;
    }
    EXPECT_NEAR(std::abs(dot) / std::sqrt(nb * ns), 1.0, 1e-5) << "mode " << i;
  }
}

// The block Lanczos modes themselves: M-orthonormal to round-off after many blocks (one
// Gram-Schmidt pass with the DGKS repeat must keep the basis orthogonal), each an eigenpair to
// the tolerance, and the symmetric block product the iteration uses equal to Eigen's.
TEST(ModalFem, BlockLanczosModesAreMOrthonormalEigenpairs) {
  const auto [fem, km] = steel_box(4e-6);
  ASSERT_GT(km.K.rows(), 3000);
  EigenOptions o;
  o.modes = 80;
  o.max_frequency = 1e6;  // the first 80, wherever they lie (44 lie below 20 kHz)
  const EigenResult r = solve_modes(km.K, km.M, rigid_body_modes(fem.nodes), o);
  ASSERT_EQ(r.lambda.size(), 80u);
  EXPECT_GT(r.operations, 2 * 86u);  // many blocks: room for orthogonality to drift
  const Eigen::MatrixXd G = r.vectors.transpose() * (km.M * r.vectors);
  EXPECT_LT((G - Eigen::MatrixXd::Identity(80, 80)).cwiseAbs().maxCoeff(), 1e-9);
  for (std::size_t i = 0; i < 80; ++i) {
    EXPECT_LT(r.residual[i], 1e-6) << "mode " << i;
    if (i > 0) {
      EXPECT_GE(r.lambda[i], r.lambda[i - 1]);
    }
  }
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(km.M.rows(), 21), Y;  // 16 + 5 columns
  for (const SparseMatrix* A : {&km.M, &km.K}) {
    symmetric_product(*A, X, Y);
    const Eigen::MatrixXd E = *A * X;
    EXPECT_LT((Y - E).norm(), 1e-13 * E.norm());
  }
}

// A band search returns converged modes only: stopped by --mode-cap, the first modes of the
// band with small residuals; with a basis too small for the band, a refusal for memory, never
// the unconverged Ritz pairs (which would be wrong modes); and with the band's size known, the
// memory check refuses that before the factorization. The first N below a band's top that holds
// fewer are the band's modes, found as cheaply, not the first N with the rest discarded.
TEST(ModalFem, BandSearchKeepsOnlyConvergedModes) {
  const auto [fem, km] = steel_box(4e-6);
  const Eigen::MatrixXd rigid = rigid_body_modes(fem.nodes);
  EigenOptions o;
  o.modes = 80;
  o.max_frequency = 1e6;
  const EigenResult first = solve_modes(km.K, km.M, rigid, o);
  ASSERT_EQ(first.lambda.size(), 80u);
  o.modes = 0;  // the band below the middle of the 50th and 51st modes: 50 modes
  o.max_frequency = 0.5 * (hz(std::sqrt(first.lambda[49])) + hz(std::sqrt(first.lambda[50])));
  const EigenResult band = solve_modes(km.K, km.M, rigid, o);
  ASSERT_EQ(band.lambda.size(), 50u);
  EXPECT_FALSE(band.capped);
  o.modes = 80;
  const EigenResult first_n = solve_modes(km.K, km.M, rigid, o);
  ASSERT_EQ(first_n.lambda.size(), 50u);
  EXPECT_FALSE(first_n.capped);
  EXPECT_LT(first_n.operations, first.operations);
  for (std::size_t i = 0; i < 50; ++i) {
    EXPECT_NEAR(first_n.lambda[i] / first.lambda[i], 1.0, 1e-8) << "mode " << i;
    EXPECT_LT(first_n.residual[i], 1e-6) << "mode " << i;
  }
  o.modes = 20;  // fewer than the band holds: the first 20
  EXPECT_EQ(solve_modes(km.K, km.M, rigid, o).lambda.size(), 20u);
  o.modes = 0;

  o.mode_cap = 12;
  const EigenResult capped = solve_modes(km.K, km.M, rigid, o);
  ASSERT_EQ(capped.lambda.size(), 12u);
  EXPECT_TRUE(capped.capped);
  for (std::size_t i = 0; i < 12; ++i) {
    EXPECT_LT(capped.residual[i], 1e-6) << "mode " << i;
    EXPECT_NEAR(capped.lambda[i] / first.lambda[i], 1.0, 1e-8) << "mode " << i;
  }

  // A budget that leaves the smallest basis (4 blocks of 8) for the 56 modes of the band.
  o.mode_cap = 2000;
  const double n = double(km.K.rows());
  o.max_memory = band.factor_bytes + band.matrix_bytes + 8.0 * n * 34.5;
  try {
    solve_modes(km.K, km.M, rigid, o);
    ADD_FAILURE() << "a basis of 32 vectors cannot converge 56 modes";
  } catch (const BudgetError& e) {
    EXPECT_NE(std::string(e.what()).find("converged"), std::string::npos) << e.what();
  }
  o.expected_modes = 50;
  try {
    solve_modes(km.K, km.M, rigid, o);
    ADD_FAILURE() << "the check should refuse before the factorization";
  } catch (const BudgetError& e) {
    EXPECT_NE(std::string(e.what()).find("would need"), std::string::npos) << e.what();
  }
}

// N modes asked for are N at or above min_frequency: those below come first, and do not count.
TEST(ModalFem, ModesBelowTheBandDoNotCountTowardN) {
  const auto [fem, km] = steel_box(4e-6);
  const Eigen::MatrixXd rigid = rigid_body_modes(fem.nodes);
  EigenOptions o;
  o.modes = 40;
  o.max_frequency = 1e6;
  const EigenResult all = solve_modes(km.K, km.M, rigid, o);
  ASSERT_EQ(all.lambda.size(), 40u);
  o.min_frequency = 0.5 * (hz(std::sqrt(all.lambda[8])) + hz(std::sqrt(all.lambda[9])));
  o.modes = 20;  // 9 below the bottom, then 20
  for (auto method : {EigenOptions::Method::BlockLanczos, EigenOptions::Method::Spectra}) {
    o.method = method;
    const EigenResult r = solve_modes(km.K, km.M, rigid, o);
    ASSERT_EQ(r.lambda.size(), 29u) << int(method);
    for (std::size_t i = 0; i < 29; ++i) {
      EXPECT_NEAR(r.lambda[i] / all.lambda[i], 1.0, 1e-8) << "mode " << i;
      EXPECT_LT(r.residual[i], 1e-6) << "mode " << i;
    }
  }
  // Where the band's top comes first, the modes below the bottom are still all there.
  o.method = EigenOptions::Method::BlockLanczos;
  o.max_frequency = 0.5 * (hz(std::sqrt(all.lambda[14])) + hz(std::sqrt(all.lambda[15])));
  EXPECT_EQ(solve_modes(km.K, km.M, rigid, o).lambda.size(), 15u);
}

#ifdef CHLADNI_HAVE_CHOLMOD
// The factorization orders K - sigma M by its node graph (3 x 3 blocks): about the fill of
// ordering the scalar matrix, and still a correct factor where the blocks are not nodes.
TEST(ModalFem, NodeGraphOrderingFactorsCorrectly) {
  const auto [fem, km] = steel_box(1e-5);
  const Eigen::Index n = km.K.rows();
  ASSERT_EQ(n % 3, 0);
  SparseMatrix A = km.K + 1e7 * km.M;  // positive definite
  A.makeCompressed();
  // Nodes scattered: DOF d goes to (d * s) mod n, s coprime with n, so no 3 x 3 block is a node.
  Eigen::Index s = 7919;
  while (std::gcd(s, n) != 1) s += 2;
  Eigen::VectorXi to(n);
  for (Eigen::Index d = 0; d < n; ++d) to(d) = int((d * s) % n);
  const Eigen::PermutationMatrix<Eigen::Dynamic> P(to);
  SparseMatrix scattered;
  scattered = A.twistedBy(P);
  scattered.makeCompressed();
  const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
  double scalar_entries = 0;
  for (int block : {1, 3}) {
    for (const SparseMatrix* m : {&A, &scattered}) {
      CholmodFactor f;
      const FactorEstimate e = f.analyze(*m, block);
      if (block == 1 && m == &A) scalar_entries = e.entries;
      if (block == 3 && m == &A) {
        EXPECT_LT(e.entries, 1.1 * scalar_entries);
      }
      ASSERT_TRUE(f.factorize(*m));
      Eigen::VectorXd x = b;  // x <- P^T L^-T L^-1 P b = m^-1 b
      f.lower_solve(x.data(), n, 1);
      f.upper_solve(x.data(), n, 1);
      EXPECT_LT((*m * x - b).norm(), 1e-9 * b.norm()) << "block " << block;
    }
  }
}

// K - sigma M is factorized from K and M without forming it: the solves are those of the sum,
// and an added matrix with an entry outside the analyzed pattern is refused, not dropped.
TEST(ModalFem, FactorizesASumWithoutFormingIt) {
  const auto [fem, km] = steel_box(1e-5);
  const Eigen::Index n = km.K.rows();
  ASSERT_LT(km.M.nonZeros(), km.K.nonZeros());  // M's pattern is a part of K's
  CholmodFactor f;
  f.analyze(km.K, 3);
  ASSERT_TRUE(f.factorize(km.K, 1e7, &km.M));
  const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
  Eigen::VectorXd x = b;
  f.lower_solve(x.data(), n, 1);
  f.upper_solve(x.data(), n, 1);
  EXPECT_LT((km.K * x + 1e7 * (km.M * x) - b).norm(), 1e-9 * b.norm());
  EXPECT_FALSE(f.factorize(km.K, -1e12, &km.M));  // far below the lowest mode: indefinite
  SparseMatrix outside(n, n);
  outside.insert(0, n - 1) = 1.0;  // DOFs of nodes that share no element
  outside.insert(n - 1, 0) = 1.0;
  outside.makeCompressed();
  ASSERT_EQ(km.K.coeff(0, n - 1), 0.0);
  EXPECT_THROW(f.factorize(km.K, 1.0, &outside), InternalError);
}
#endif

#ifdef CHLADNI_HAVE_CHOLMOD
// The memory check orders the node graph as the factorization would (AMD and METIS, the better
// kept), so the factorization reuses its ordering: the same factor and modes, ordered once. Its
// estimate is then the factor's own size.
TEST(ModalFem, FactorizationReusesTheMemoryChecksOrdering) {
  const auto [fem, km] = steel_box(1e-5);
  EigenOptions o;
  o.modes = 6;
  o.max_memory = 1e12;
  EigenOptions given = o;
  check_memory_for_mesh(fem, o, &given.node_ordering);
  ASSERT_EQ(given.node_ordering.size(), fem.nodes.size());
  std::vector<std::int64_t> sorted = given.node_ordering;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t k = 0; k < sorted.size(); ++k) ASSERT_EQ(sorted[k], std::int64_t(k));
  const Eigen::MatrixXd rigid = rigid_body_modes(fem.nodes);
  const EigenResult own = solve_modes(km.K, km.M, rigid, o);
  const EigenResult reused = solve_modes(km.K, km.M, rigid, given);
  EXPECT_EQ(reused.factor_entries, own.factor_entries);
  EXPECT_EQ(reused.factor_flops, own.factor_flops);
  ASSERT_EQ(reused.lambda.size(), own.lambda.size());
  for (std::size_t i = 0; i < own.lambda.size(); ++i)
    EXPECT_NEAR(reused.lambda[i] / own.lambda[i], 1.0, 1e-10);
  // A reversed ordering is honoured too: a different factor, the same modes.
  EigenOptions reversed = given;
  std::reverse(reversed.node_ordering.begin(), reversed.node_ordering.end());
  const EigenResult other = solve_modes(km.K, km.M, rigid, reversed);
  EXPECT_NE(other.factor_entries, own.factor_entries);
  for (std::size_t i = 0; i < own.lambda.size(); ++i)
    EXPECT_NEAR(other.lambda[i] / own.lambda[i], 1.0, 1e-9);
}
#endif

// A box given as 12 triangles must get the elements the volume bound asks for (TetGen alone,
// keeping the surface, would leave it 12 tetrahedra), and so the same modes as the same box
// given with a fine surface.
TEST(ModalFem, CoarseSurfaceBoxMatchesFineSurfaceBox) {
  const Vec3 size{0.3, 0.18, 0.12};
  PrecomputeOptions o;
  o.max_modes = 8;
  o.transfer = false;
  PrecomputeReport coarse_r, fine_r;
  const Soundbank coarse =
      precompute_surface(test::box_surface(size, {1, 1, 1}), "coarse box", o, coarse_r);
  const Soundbank fine =
      precompute_surface(test::box_surface(size, {10, 6, 4}), "fine box", o, fine_r);
  EXPECT_GT(coarse.triangles.size(), 12u);  // the surface was split for the elements
  ASSERT_EQ(coarse.omega.size(), 8u);
  ASSERT_EQ(fine.omega.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i)
    EXPECT_NEAR(coarse.omega[i] / fine.omega[i], 1.0, 0.01) << "mode " << i;
}

// The memory figure found before meshing, from coarser meshes, is a lower bound on the one the
// mesh itself gives (so a refusal before meshing never refuses what would fit), and not a
// vacuous one: a solid box, a thin shell and Spot.
TEST(ModalFem, MemoryBeforeMeshingIsALowerBound) {
  EigenOptions eo;
  eo.max_memory = 1e15;         // report, never refuse
  eo.modes = eo.mode_cap = 20;  // a small basis: the factor and the matrices decide
  for (const char* name : {"bar.obj", "bowl.obj", "spot.obj"}) {
    const SurfaceMesh s = read_mesh(kMeshes + "/" + name);
    TetOptions o;
    o.max_volume = coarse_max_volume(s) / 40;
    const double lower =
        check_memory_for_surface(s, std::abs(check_mesh(s).volume), o.max_volume, 2, o, eo);
    const double exact = check_memory_for_mesh(make_fem_mesh(tetrahedralize(s, o), 2), eo);
    EXPECT_GT(lower, 0) << name;
    EXPECT_LE(lower, exact) << name;
    EXPECT_GT(lower, exact / 5) << name;  // measured: 0.31, 1 and 0.91 of it
  }
}
