#include "eigen_memory.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "../huge_pages.hpp"
#include "chladni/core/error.hpp"
#include "shift_invert.hpp"

namespace chladni::precompute {
namespace {

// The eigen-solve's memory has two peaks besides the factor. Factorizing: K (a double and an int
// per entry), M (the same for a third of the entries), the upper triangle of K - sigma M in long
// indices (a double and a long for half the entries) and CHOLMOD's permuted copy of it (the
// same): 32 bytes per entry of K. Iterating: K, M and the kept pattern (20 bytes per entry), the
// Lanczos basis and the Ritz vectors (the modes). kFactorizingBytesPerEntry: eigen_memory.hpp.
constexpr double kIteratingBytesPerEntry = 12 + 4 + 4;

// The modes the Lanczos run must hold, the six rigid ones included: those asked for, or those
// expected below max_frequency within the cap; 0 where unknown (a band of unknown size).
Eigen::Index ritz_columns(Eigen::Index n, const EigenOptions& o) {
  const std::size_t modes = o.modes > 0 ? o.modes : std::min(o.expected_modes, o.mode_cap);
  return modes == 0 ? 0 : std::min<Eigen::Index>(n, Eigen::Index(modes) + 6);
}

// The smallest basis worth factorizing for: modes converge in about 3.3 vectors per mode (352
// for spot.obj's 106), so 4 per mode and two blocks.
Eigen::Index lanczos_floor(Eigen::Index n, const EigenOptions& o) {
  const Eigen::Index ritz = ritz_columns(n, o);
  return std::min<Eigen::Index>(n, ritz > 0 ? 4 * ritz + 2 * o.block : 4 * o.block);
}

// CHOLMOD's analysis of the node graph, where each element couples all its nodes. K's pattern is
// this graph with each entry a 3 x 3 block, so its factor has 9 times the entries and 27 times
// the flops. `entries` receives the entries of K.
FactorEstimate node_graph_estimate(const FemMesh& mesh, double& entries,
                                   std::vector<std::int64_t>* ordering = nullptr) {
  const int npe = mesh.nodes_per_element();
  std::vector<Eigen::Triplet<double, int>> t;
  t.reserve(mesh.element_count() * std::size_t(npe * npe));
  advise_huge_pages(t.data(), sizeof(t[0]) * t.capacity());
  for (std::size_t e = 0; e < mesh.element_count(); ++e)
    for (int a = 0; a < npe; ++a)
      for (int b = 0; b < npe; ++b)
        t.emplace_back(int(mesh.elements[e * npe + a]), int(mesh.elements[e * npe + b]),
                       a == b ? 1.0 : 0.0);
  SparseMatrix G(Eigen::Index(mesh.nodes.size()), Eigen::Index(mesh.nodes.size()));
  G.setFromTriplets(t.begin(), t.end());
  G.makeCompressed();
  t = {};
  Factor f;
  FactorEstimate est = f.analyze(G, 1, nullptr);
  if (ordering) *ordering = f.ordering();
  est.entries *= 9, est.bytes *= 9, est.flops *= 27;
  entries = 9.0 * double(G.nonZeros());
  return est;
}

}  // namespace

std::string gigabytes(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f GB", bytes / 1e9);
  return buf;
}

// The largest basis: twice the floor for the cap's modes (clusters of close modes, a cube's or
// a box's, can take 6 vectors per mode where they are few), where the budget leaves room for it
// after the factor, the matrices and the Ritz vectors (`reserved`), but never below the floor
// (the budget check refuses that case). `by_memory` says whether the budget, not the count, set
// it. The basis grows only as the iteration needs it.
Eigen::Index lanczos_dim(Eigen::Index n, double reserved, const EigenOptions& o, bool* by_memory) {
  const Eigen::Index max_nev = std::min<Eigen::Index>(n - 2, Eigen::Index(o.mode_cap) + 6);
  const Eigen::Index target = std::min<Eigen::Index>(n, 8 * max_nev + 4 * o.block);
  Eigen::Index dim = target;
  if (o.max_memory > 0)
    dim = std::min<Eigen::Index>(
        dim, Eigen::Index(std::max(0.0, o.max_memory - reserved) / (8.0 * double(n))));
  if (by_memory) *by_memory = dim < target;
  return std::max(dim, lanczos_floor(n, o));
}

// What the eigen-solve needs at most: the factor with whichever phase is larger. Refuses
// (BudgetError) above the budget, with the parts.
double check_budget(Eigen::Index n, const FactorEstimate& est, double entries,
                    const EigenOptions& o, const std::string& how, const char* amount) {
  const double factorizing = kFactorizingBytesPerEntry * entries;
  const double basis = 8.0 * double(n) * double(lanczos_floor(n, o) + ritz_columns(n, o));
  const double iterating = kIteratingBytesPerEntry * entries + basis;
  const double need = est.bytes + std::max(factorizing, iterating);
  if (o.max_memory <= 0 || need <= o.max_memory) return need;
  throw BudgetError(
      "the eigen-solve would need " + std::string(amount) + gigabytes(need) +
      " (the sparse factor of K - sigma M for " + std::to_string(n) +
      " DOFs: " + gigabytes(est.bytes) + ", nnz(L) " + std::to_string(std::llround(est.entries)) +
      ", " + std::to_string(std::llround(est.flops / 1e9)) +
      " GFLOP; the matrices and their copies while it is computed: " + gigabytes(factorizing) +
      "; afterwards the matrices, the Lanczos basis and the modes: " + gigabytes(iterating) + how +
      "), more than the memory budget of " + gigabytes(o.max_memory) +
      ": raise --max-tet-volume (coarser elements), lower --max-freq or "
      "--max-modes, or raise --max-memory");
}

// The bytes the iteration may count on before the basis: the factor, the matrices and the
// Ritz vectors.
double iteration_reserve(Eigen::Index n, const FactorEstimate& est, double entries,
                         const EigenOptions& o) {
  return est.bytes + kIteratingBytesPerEntry * entries + 8.0 * double(n) * ritz_columns(n, o);
}

double default_memory_budget() {
  // MemAvailable counts what can be had without swapping (free plus reclaimable caches).
  std::ifstream in("/proc/meminfo");
  for (std::string line; std::getline(in, line);) {
    double kb = 0;
    if (std::sscanf(line.c_str(), "MemAvailable: %lf kB", &kb) == 1) return 0.8 * kb * 1024.0;
  }
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? 0.8 * double(pages) * double(size) : 0.0;
}

double check_memory_for_mesh(const FemMesh& mesh, const EigenOptions& o,
                             std::vector<std::int64_t>* node_ordering) {
  if (o.max_memory <= 0) return 0;
  double entries = 0;
  const FactorEstimate est = node_graph_estimate(mesh, entries, node_ordering);
  if (est.bytes <= 0) return 0;  // this build's factorization cannot say before factorizing
  return check_budget(Eigen::Index(mesh.dofs()), est, entries, o,
                      "; estimated from the mesh before assembly");
}

double check_memory_extrapolated(const FemMesh& coarse, const FemMesh& sample, double tetrahedra,
                                 const EigenOptions& o) {
  if (o.max_memory <= 0) return 0;
  // DOFs per tetrahedron, at most what a large quality mesh has (P2: 1.32 nodes per tetrahedron
  // from Euler's formula with about 6.3 tetrahedra per vertex, so 3.95 DOFs; P1: 0.48) and never
  // above the sample's own, where the surface's share is larger.
  const double ns = double(sample.dofs());
  const bool p2 = sample.nodes_per_element() == 10;
  const double n =
      std::max(ns, std::min(p2 ? 3.6 : 0.4, ns / double(sample.element_count())) * tetrahedra);
  double entries = 0;
  FactorEstimate est = node_graph_estimate(sample, entries);
  if (est.bytes <= 0) return 0;
  // Nested dissection's factor grows as n^(4/3) in a solid and n log n in a shell, and a thin
  // part grows faster once its thickness is resolved: the growth between the two meshes,
  // within [1, 4/3] (flops [1, 2]), extrapolated from the finer one can only underestimate.
  // Where the two are alike (a surface that decides the mesh), only the floors are known.
  const double r = std::log(n / ns), rs = std::log(ns / double(coarse.dofs()));
  double a = 1, af = 1;
  if (rs > 0.05) {
    double unused = 0;
    const FactorEstimate low = node_graph_estimate(coarse, unused);
    a = std::clamp(std::log(est.entries / low.entries) / rs, 1.0, 4.0 / 3.0);
    af = std::clamp(std::log(est.flops / low.flops) / rs, 1.0, 2.0);
  }
  est.entries *= std::exp(a * r), est.bytes *= std::exp(a * r), est.flops *= std::exp(af * r);
  entries *= n / ns;
  return check_budget(Eigen::Index(n), est, entries, o,
                      "; a lower bound found before meshing, from meshes of " +
                          std::to_string(coarse.element_count()) + " and " +
                          std::to_string(sample.element_count()) + " tetrahedra extrapolated to " +
                          std::to_string(std::llround(tetrahedra)),
                      "at least ");
}

}  // namespace chladni::precompute
