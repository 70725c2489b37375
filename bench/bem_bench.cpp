// Boundary-element transfer speed (docs/PERFORMANCE.md, "Boundary elements"): per surface size,
// the one-time near-field cache, the per-frequency assembly, the LU (double below the direct
// limit, single precision above) and GMRES, for a few frequencies a small step apart; plus the
// multipole quadrature. Surfaces: icospheres of radius 0.1 m (level L: 20 x 4^L triangles) or
// mesh files, optionally split (FILE@S: each triangle split into 4, S times, as the transfer does).
// Above BemOptions::hmatrix_limit elements the system is a hierarchical matrix; "LU" is then its
// hierarchical LU.
// Usage: chladni_bem_bench [SURFACE ...] [--freq HZ] [--steps N] [--step REL] [--backend cpu|gpu]
//                          [--refactor-phase RAD] [--hmatrix-limit N] [--lu-epsilon E]
//                          [--json OUT]
//        (gpu: the centroid-rule rows on the Vulkan device, kernels/bem_far.comp)
//        SURFACE: icosphere:L, FILE or FILE@S (default icosphere:3 icosphere:4 meshes/bowl.obj)
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../tests/fem_fixtures.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/precompute/bem.hpp"

using namespace chladni;
using cd = std::complex<double>;

static double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

static precompute::SurfaceMesh load(const std::string& s) {
  if (s.rfind("icosphere:", 0) == 0) return test::icosphere(0.1, std::stoi(s.substr(10)));
  const std::size_t at = s.rfind('@');
  if (at == std::string::npos) return precompute::read_mesh(s);
  return precompute::BemSurface(precompute::read_mesh(s.substr(0, at)), std::stoi(s.substr(at + 1)))
      .mesh;
}

int main(int argc, char** argv) {
  std::vector<std::string> surfaces;
  double freq = 2000;
  int steps = 3;
  double step = 0.005, refactor_phase = -1, lu_epsilon = -1;
  long hmatrix_limit = -1;
  std::string json_path, backend = "cpu";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--freq") && i + 1 < argc)
      freq = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--steps") && i + 1 < argc)
      steps = std::stoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--hmatrix-limit") && i + 1 < argc)
      hmatrix_limit = std::stol(argv[++i]);
    else if (!std::strcmp(argv[i], "--refactor-phase") && i + 1 < argc)
      refactor_phase = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--lu-epsilon") && i + 1 < argc)
      lu_epsilon = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--step") && i + 1 < argc)
      step = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--backend") && i + 1 < argc)
      backend = argv[++i];
    else if (!std::strcmp(argv[i], "--json") && i + 1 < argc)
      json_path = argv[++i];
    else
      surfaces.push_back(argv[i]);
  }
  if (surfaces.empty()) surfaces = {"icosphere:3", "icosphere:4", "meshes/bowl.obj"};
  nlohmann::json out = nlohmann::json::array();
  std::printf("%-18s %7s %9s %12s %10s %10s %8s %12s\n", "surface", "N", "cache(s)", "assembly(s)",
              "LU(s)", "GMRES(s)", "iters", "multipole(s)");
  for (const std::string& name : surfaces) {
    const precompute::BemMesh mesh(load(name));
    precompute::BemOptions o;
    if (refactor_phase >= 0) o.refactor_phase = refactor_phase;
    if (hmatrix_limit >= 0) o.hmatrix_limit = std::size_t(hmatrix_limit);
    if (lu_epsilon > 0) o.hmatrix_lu_epsilon = lu_epsilon;
    if (backend == "gpu") o.gpu = std::make_shared<gpu::Context>();
    precompute::BemSolver solver(mesh, o);
    std::vector<cd> q(mesh.elements());
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = mesh.normal[j][2];  // a rigid shake in z
    double first_assembly = 0, multipole = 0;
    int iterations = 0;
    for (int s = 0; s < steps; ++s) {
      const double k = 2 * std::numbers::pi * freq * (1 + step * s) / 343.0;
      const auto res = solver.solve(k, q);
      if (s == 0) first_assembly = solver.times().assembly;
      iterations += res.iterations;
      std::fprintf(stderr, "  step %d: k %.2f, %d iterations%s\n", s, k, res.iterations,
                   res.factorized ? ", factorized" : "");
      const auto t0 = std::chrono::steady_clock::now();
      precompute::bem_multipoles(mesh, k, {0, 0, 0}, 20, res.pressure, q);
      multipole += since(t0);
    }
    const auto& t = solver.times();
    const double per = steps > 1 ? (t.assembly - first_assembly) / (steps - 1) : first_assembly;
    const double cache = first_assembly - per;
    std::printf("%-18s %7zu %9.2f %12.2f %10.2f %10.2f %8.1f %12.3f\n", name.c_str(),
                mesh.elements(), cache, per, t.factorization, t.iteration / steps,
                double(iterations) / steps, multipole / steps);
    out.push_back({{"surface", name},
                   {"backend", backend == "gpu" ? o.gpu->info().name : std::string("cpu")},
                   {"elements", mesh.elements()},
                   {"frequency_hz", freq},
                   {"frequency_step", step},
                   {"hierarchical", mesh.elements() > o.hmatrix_limit},
                   {"near_cache_s", cache},
                   {"assembly_per_frequency_s", per},
                   {"lu_total_s", t.factorization},
                   {"gmres_per_frequency_s", t.iteration / steps},
                   {"gmres_iterations_per_frequency", double(iterations) / steps},
                   {"multipoles_L20_s", multipole / steps}});
  }
  if (!json_path.empty()) std::ofstream(json_path) << out.dump(2) << '\n';
  return 0;
}
