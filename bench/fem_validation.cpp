// FEM convergence against analytic elasticity, printed as the markdown tables of
// docs/validation.md: a free-free steel bar (box surface refined with the volume) against
// Timoshenko beam theory, and a free steel sphere (refined icosphere) against Lamb's solution,
// for linear (P1) and quadratic (P2) tetrahedra.
//   ./build/bench/chladni_fem_validation            (about a minute on two cores)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "chladni/precompute.hpp"
#include "elastic_reference.hpp"
#include "fem_fixtures.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

struct Row {
  std::size_t tets = 0, dofs = 0;
  double seconds = 0;
  Soundbank bank;
};

Row solve(const SurfaceMesh& s, int order, double edge, std::size_t modes) {
  PrecomputeOptions o;
  o.order = order;
  o.max_modes = modes;
  o.max_tet_volume = edge * edge * edge / (6 * std::sqrt(2.0));
  PrecomputeReport r;
  const auto t0 = std::chrono::steady_clock::now();
  Row row;
  row.bank = precompute_surface(s, "generated", o, r);
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  row.tets = r.tets, row.dofs = r.dofs;
  return row;
}

double hz(double w) {
  return w / (2 * std::numbers::pi);
}

}  // namespace

int main() {
  const Material steel = find_material("steel");
  const double E = steel.youngs_modulus, nu = steel.poisson_ratio, rho = steel.density;

  // Bar 0.3 x 0.03 x 0.01 m: first bending across the thickness and across the width.
  const double L = 0.3, W = 0.03, H = 0.01, kappa = test::cowper_rectangle(nu);
  const double fz =
      test::timoshenko_free_free(L, E, nu, rho, W * H, W * H * H * H / 12, kappa, 1)[0];
  const double fy =
      test::timoshenko_free_free(L, E, nu, rho, W * H, H * W * W * W / 12, kappa, 1)[0];
  std::printf(
      "### Free-free steel bar 0.3 x 0.03 x 0.01 m (Timoshenko: %.2f Hz across the thickness, %.2f "
      "Hz across the width)\n\n",
      fz, fy);
  std::printf(
      "| order | surface grid | tets | DOFs | f1 thickness (Hz) | error | f1 width (Hz) | error | "
      "time (s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  const std::array<int, 3> grids[] = {{15, 2, 1}, {30, 3, 1}, {60, 6, 2}, {120, 12, 4}};
  for (int order : {1, 2}) {
    for (const auto& g : grids) {
      if (order == 2 && g[0] > 60) continue;  // converged; keeps the run short
      const double edge = L / g[0];
      const Row row = solve(test::box_surface({L, W, H}, g), order, edge, 12);
      const auto kinds = test::classify_bar_modes(row.bank);
      double z = NAN, y = NAN;
      for (std::size_t i = 0; i < row.bank.mode_count(); ++i) {
        if (std::isnan(z) && kinds[i] == test::BarMode::BendZ) z = hz(row.bank.omega[i]);
        if (std::isnan(y) && kinds[i] == test::BarMode::BendY) y = hz(row.bank.omega[i]);
      }
      std::printf("| P%d | %d x %d x %d | %zu | %zu | %.2f | %+.2f%% | %.2f | %+.2f%% | %.2f |\n",
                  order, g[0], g[1], g[2], row.tets, row.dofs, z, 100 * (z / fz - 1), y,
                  100 * (y / fy - 1), row.seconds);
      std::fflush(stdout);
    }
  }

  // Sphere of radius 0.1 m: the gravest (torsional, n = 2) and the spheroidal n = 2 modes.
  const double a = 0.1, cs = steel.shear_speed();
  const double ft = test::lamb_torsional(2, 4)[0] * cs / (2 * std::numbers::pi * a);
  const double fs = test::lamb_spheroidal(2, nu, 4)[0] * cs / (2 * std::numbers::pi * a);
  std::printf(
      "\n### Free steel sphere, radius 0.1 m (Lamb: torsional n=2 %.1f Hz, spheroidal n=2 %.1f "
      "Hz)\n\n",
      ft, fs);
  std::printf(
      "| order | icosphere level | tets | DOFs | torsional n=2 (Hz, mean of 5) | error | "
      "spheroidal n=2 (Hz, mean of 5) | error | time (s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (int order : {1, 2}) {
    for (int level : {1, 2, 3, 4}) {
      if (order == 2 && level > 3) continue;
      const double edge = a * 1.05 / (1 << level);  // icosahedron edge / 2^level
      const Row row = solve(test::icosphere(a, level), order, edge, 10);
      // The ten lowest modes are the two five-fold multiplets; split them at the larger gap.
      std::vector<double> f;
      for (double w : row.bank.omega) f.push_back(hz(w));
      double t = 0, s = 0;
      const bool torsional_first = std::abs(f[0] - ft) < std::abs(f[0] - fs);
      for (int i = 0; i < 5; ++i) (torsional_first ? t : s) += f[i] / 5;
      for (int i = 5; i < 10; ++i) (torsional_first ? s : t) += f[i] / 5;
      std::printf("| P%d | %d | %zu | %zu | %.1f | %+.2f%% | %.1f | %+.2f%% | %.2f |\n", order,
                  level, row.tets, row.dofs, t, 100 * (t / ft - 1), s, 100 * (s / fs - 1),
                  row.seconds);
      std::fflush(stdout);
    }
  }
  return 0;
}
