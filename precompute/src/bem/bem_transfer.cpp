// Acoustic transfer by boundary elements: per mode the Burton-Miller solve on the surface, the
// multipole coefficients by quadrature, the expansion's truncation check and an interior
// null-field check of the surface solution.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <thread>

#include "../blas_threads.hpp"
#include "../surface/surface_pieces.hpp"
#include "../timing.hpp"
#include "bem_side_process.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"

namespace chladni::precompute {
namespace {

using cd = std::complex<double>;

std::string memory_text(double bytes) {
  char text[32];
  if (bytes < 1e9)
    std::snprintf(text, sizeof text, "%.0f MB", bytes / 1e6);
  else
    std::snprintf(text, sizeof text, "%.2f GB", bytes / 1e9);
  return text;
}

// The representation p(x) = int p dG/dn_y - q G vanishes inside the body: its size there,
// against the size of either term, measures how consistent the surface pressure is with the data.
double null_field_error(const BemMesh& mesh, double k, const std::vector<cd>& p,
                        const std::vector<cd>& q, const std::vector<Vec3>& points,
                        const BemOptions& o) {
  if (points.empty()) return 0.0;
  const std::vector<cd> zero(p.size(), cd(0.0));
  const std::vector<cd> dbl = bem_field(mesh, k, p, zero, points, o);
  const std::vector<cd> sgl = bem_field(mesh, k, zero, q, points, o);  // -int q G
  double num = 0, den = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    num += std::norm(dbl[i] + sgl[i]);
    den += std::max(std::norm(dbl[i]), std::norm(sgl[i]));
  }
  return den > 0 ? std::sqrt(num / den) : 0.0;
}

// Generalized winding number of the surface about x: 1 inside a closed outward surface, 0 outside.
double winding_number(const SurfaceMesh& m, const Vec3& x) {
  double sum = 0;
  for (const auto& t : m.triangles)
    sum += solid_angle(x, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]);
  return sum / (4 * std::numbers::pi);
}

}  // namespace

double bem_memory(std::size_t n, const BemOptions& o) {
  const double N = double(n);
  // Measured peak resident memory of the hierarchical solve: 226-236 kB per element on the bell
  // (10,880 elements, 3 kHz) and the split bowl (26,112, 13 kHz), 165 kB on the split bar.
  if (n > o.hmatrix_limit) return 256e3 * N;
  // Dense: the matrix, its LU (single precision above the direct limit) and the near cache.
  return (n > o.direct_limit ? 24.0 : 32.0) * N * N + 8e3 * N;
}

int bem_level(const RadiatingSurface& surface, double k, const AcousticOptions& o) {
  const double target = 2 * std::numbers::pi / o.bem_elements_per_wavelength;
  double n = double(surface.mesh().triangles.size()), h = surface.mean_element_size();
  const bool forced = o.method == AcousticOptions::Method::Bem;
  const double cap = double(forced ? o.bem_max_elements : o.bem_auto_elements);
  auto fits = [&](double elements) {
    return elements <= cap &&
           (o.bem_max_memory <= 0 || bem_memory(std::size_t(elements), o.bem) <= o.bem_max_memory);
  };
  int best = -1, extra = o.bem_extra_levels;
  for (int level = 0; level <= 4 && fits(n); ++level, n *= 4, h /= 2) {
    best = level;
    if (h * k <= target && extra-- == 0) return level;
  }
  if (!forced) return -1;
  if (best < 0) {
    const double need = bem_memory(surface.mesh().triangles.size(), o.bem);
    throw BudgetError("transfer: boundary elements on the " +
                      std::to_string(surface.mesh().triangles.size()) + " surface triangles need " +
                      memory_text(need) + ", more than --max-memory allows (" +
                      memory_text(o.bem_max_memory) +
                      "): raise --max-memory or use --transfer-method auto or sources");
  }
  return best;
}

AcousticOptions::Method resolve_method(const RadiatingSurface& surface, double k,
                                       const AcousticOptions& o) {
  using M = AcousticOptions::Method;
  if (o.method != M::Auto) return o.method;
  if (o.bem_cheap_elements > 0) {
    AcousticOptions cheap = o;
    cheap.bem_auto_elements = std::min(o.bem_auto_elements, o.bem_cheap_elements);
    if (bem_level(surface, k, cheap) >= 0) return M::Bem;
  }
  if (k * surface.radius() < o.bem_compact_kr && bem_level(surface, k, o) >= 0) return M::Bem;
  if (wave_fits(surface, k, o)) return M::Wave;
  return bem_level(surface, k, o) >= 0 ? M::Bem : M::Sources;
}

bool wave_fits(const RadiatingSurface& surface, double k, const AcousticOptions& o) {
  const WaveLayout layout = wave_layout(surface.mesh(), o.wave);
  const double hz = k * o.sound_speed / (2 * std::numbers::pi);
  const Chord alone{{0}, hz, hz, 0.0};
  const WaveGridSize s = wave_grid_size(layout, alone, o.sound_speed, surface.area(), o.wave);
  return (o.wave.max_memory <= 0 || s.bytes <= o.wave.max_memory) &&
         s.cell_steps() <= o.wave.max_cell_steps;
}

namespace {

// dp/dn = i omega rho0 u_n, averaged over each element (3 points, mapped into the parent).
std::vector<cd> element_dpdn(const BemSurface& elements, double k, const NormalVelocity& un,
                             const AcousticOptions& o) {
  const std::size_t n = elements.parent.size();
  const cd neumann(0.0, k * o.sound_speed * o.air_density);
  constexpr double kPoints[3][3] = {
      {2.0 / 3, 1.0 / 6, 1.0 / 6}, {1.0 / 6, 2.0 / 3, 1.0 / 6}, {1.0 / 6, 1.0 / 6, 2.0 / 3}};
  std::vector<cd> q(n);
  for (std::size_t j = 0; j < n; ++j) {
    cd sum = 0;
    for (const auto& b : kPoints) {
      std::array<double, 3> in_parent{0, 0, 0};
      for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 3; ++d) in_parent[d] += b[c] * elements.corners[j][c][d];
      sum += un(elements.parent[j], in_parent);
    }
    q[j] = neumann * sum / 3.0;
  }
  return q;
}

// From one solve's surface pressure: c_lm by quadrature, trimmed and checked, and the interior
// null-field check.
ModeTransfer expand_solution(const RadiatingSurface& surface, const BemMesh& mesh, double k,
                             const BemSolver::Result& res, const std::vector<cd>& q,
                             const AcousticOptions& o, std::vector<cd>& a) {
  const std::size_t n = mesh.elements();
  const double R = surface.radius();
  const int L = expansion_order(k, R, o);
  a = bem_multipoles(mesh, k, surface.centre(), L, res.pressure, q, o.bem.threads);
  std::vector<cd> h(static_cast<std::size_t>(L) + 1);
  sph_hankel1(L, k * R, h.data());
  for (int l = 0; l <= L; ++l)
    for (int m = -l; m <= l; ++m) a[sh_index(l, m)] *= h[l];
  ModeTransfer mt =
      finish_expansion(surface, k, L, a, o, [&](const std::vector<Vec3>& rel, cd* out) {
        std::vector<Vec3> pts(rel.size());
        for (std::size_t i = 0; i < rel.size(); ++i) pts[i] = add(rel[i], surface.centre());
        const std::vector<cd> f = bem_field(mesh, k, res.pressure, q, pts, o.bem);
        std::copy(f.begin(), f.end(), out);
      });
  mt.method = TransferMethod::Bem;
  mt.sources = static_cast<uint32_t>(n);
  mt.iterations = static_cast<uint16_t>(std::min(res.iterations, 65535));
  mt.fit_residual = static_cast<float>(res.residual);
  // Interior points at least 1.5 elements from every element centroid (near the surface the
  // field of piecewise-constant data is not meant to be accurate), and inside by the winding
  // number: at a concave edge of a CAD part, a vertex stepped against its averaged normal can
  // land in the air, where the representation is the radiated field, not zero.
  std::vector<Vec3> inside;
  const double clearance = 1.5 * mesh.mean_size();
  for (const Vec3& x : surface.interior_points(64, clearance)) {
    bool clear = winding_number(surface.mesh(), x) > 0.5;
    for (std::size_t j = 0; j < n && clear; ++j)
      clear = dot(sub(x, mesh.centroid[j]), sub(x, mesh.centroid[j])) >= clearance * clearance;
    if (clear && inside.size() < 16) inside.push_back(x);
  }
  mt.held_out_error = static_cast<float>(null_field_error(mesh, k, res.pressure, q, inside, o.bem));
  return mt;
}

}  // namespace

std::vector<ModeTransfer> bem_transfer(const RadiatingSurface& surface, const BemSurface& elements,
                                       const BemMesh& mesh, BemSolver& solver, double k,
                                       std::span<const NormalVelocity> un, const AcousticOptions& o,
                                       std::vector<std::vector<cd>*> a, TransferTimes* times,
                                       std::vector<cd>* pressure, std::vector<cd>* dpdn) {
  if (mesh.elements() != elements.parent.size())
    throw InternalError("bem: the boundary mesh is not the surface's elements");
  if (a.size() != un.size()) throw InternalError("bem: one coefficient vector per mode expected");
  std::vector<std::vector<cd>> qs;
  for (const NormalVelocity& u : un) qs.push_back(element_dpdn(elements, k, u, o));
  const BemSolver::Times before = solver.times();
  const std::vector<BemSolver::Result> res = solver.solve(k, qs);
  if (times) {
    const BemSolver::Times& after = solver.times();
    times->matrix += after.assembly - before.assembly;
    times->solve += after.factorization - before.factorization + after.iteration - before.iteration;
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<ModeTransfer> out;
  for (std::size_t v = 0; v < un.size(); ++v)
    out.push_back(expand_solution(surface, mesh, k, res[v], qs[v], o, *a[v]));
  if (times) times->expand += seconds_since(t0);
  if (pressure && !res.empty()) *pressure = res.front().pressure;
  if (dpdn && !qs.empty()) *dpdn = std::move(qs.front());
  return out;
}

ModeTransfer bem_transfer(const RadiatingSurface& surface, const BemSurface& elements,
                          const BemMesh& mesh, BemSolver& solver, double k,
                          const NormalVelocity& un, const AcousticOptions& o, std::vector<cd>& a,
                          TransferTimes* times, std::vector<cd>* pressure, std::vector<cd>* dpdn) {
  return bem_transfer(surface, elements, mesh, solver, k, std::span<const NormalVelocity>(&un, 1),
                      o, {&a}, times, pressure, dpdn)
      .front();
}

namespace {

// Modes solved together: one wavenumber, one element mesh.
struct ModeGroup {
  int level = 0;
  double k = 0;
  std::vector<std::size_t> modes;
};

// Consecutive modes (ascending frequency) within bem_shared_frequency of a group's first (the
// degenerate pairs and clusters of a symmetric body) form a group, solved at their mean k.
std::vector<ModeGroup> group_modes(const RadiatingSurface& surface, const Soundbank& bank,
                                   const std::vector<std::size_t>& which,
                                   const AcousticOptions& o) {
  auto wavenumber = [&](std::size_t i) { return bank.damped_omega(i) / o.sound_speed; };
  std::vector<ModeGroup> groups;
  for (std::size_t i : which) {
    const double k = wavenumber(i);
    const int level = std::max(0, bem_level(surface, k, o));
    ModeGroup* g = groups.empty() ? nullptr : &groups.back();
    if (g && g->level == level &&
        std::abs(k / wavenumber(g->modes.front()) - 1) <= o.bem_shared_frequency) {
      g->modes.push_back(i);
    } else {
      groups.push_back({level, 0.0, {i}});
    }
  }
  for (ModeGroup& g : groups) {
    for (std::size_t i : g.modes) g.k += wavenumber(i);
    g.k /= double(g.modes.size());
  }
  return groups;
}

// Solves groups in order on one solver (each LU preconditions the next frequencies).
void solve_groups(const RadiatingSurface& surface, const Soundbank& bank,
                  const BemSurface& elements, const BemMesh& mesh, BemSolver& solver,
                  std::span<const ModeGroup> groups, const AcousticOptions& o,
                  std::vector<ModeTransfer>& modes, std::vector<std::vector<cd>>& coeffs,
                  TransferTimes* times, const std::function<void(std::size_t)>& done) {
  const std::size_t nv = bank.vertices.size();
  for (const ModeGroup& g : groups) {
    std::vector<NormalVelocity> un;
    std::vector<std::vector<cd>*> a;
    for (std::size_t i : g.modes) {
      un.push_back(surface.from_mode_shape(bank.shapes.data() + i * nv * 3, bank.damped_omega(i)));
      a.push_back(&coeffs[i]);
    }
    const std::vector<ModeTransfer> mt =
        bem_transfer(surface, elements, mesh, solver, g.k, un, o, a, times);
    for (std::size_t v = 0; v < g.modes.size(); ++v) {
      // The series from R outwards at the mode's own wavenumber, so the phase far away is its.
      modes[g.modes[v]] = mt[v];
      modes[g.modes[v]].wavenumber = bank.damped_omega(g.modes[v]) / o.sound_speed;
      done(g.modes[v]);
    }
  }
}

// Two solvers at once where a solve keeps one core (hmat-oss is sequential) and the memory
// holds two systems; else one.
int solver_workers(std::size_t elements, std::size_t groups, const AcousticOptions& o) {
  const unsigned cores =
      o.bem.threads > 0 ? unsigned(o.bem.threads) : std::thread::hardware_concurrency();
  if (elements <= o.bem.hmatrix_limit || groups < 2 || o.bem_solvers == 1) return 1;
  if (o.bem_solvers == 0 && cores < 2) return 1;
  if (o.bem_max_memory > 0 && 2 * bem_memory(elements, o.bem) > o.bem_max_memory) return 1;
  return 2;
}

}  // namespace

void compute_transfer_bem(const RadiatingSurface& surface, const Soundbank& bank,
                          const std::vector<std::size_t>& which, const AcousticOptions& o,
                          std::vector<ModeTransfer>& modes, std::vector<std::vector<cd>>& coeffs,
                          TransferTimes* times, const std::function<void()>& done) {
  const std::vector<ModeGroup> groups = group_modes(surface, bank, which, o);
  for (std::size_t l0 = 0; l0 < groups.size();) {  // one element mesh per run of a level
    std::size_t l1 = l0;
    while (l1 < groups.size() && groups[l1].level == groups[l0].level) ++l1;
    const BemSurface elements(surface.mesh(), groups[l0].level);
    const BemMesh mesh(elements.mesh);
    const std::span<const ModeGroup> run(groups.data() + l0, l1 - l0);
    const auto tick = [&](std::size_t) {
      if (done) done();
    };
    if (solver_workers(mesh.elements(), run.size(), o) == 1) {
      BemSolver solver(mesh, o.bem);
      solve_groups(surface, bank, elements, mesh, solver, run, o, modes, coeffs, times, tick);
    } else {
      // The lower and the upper half of the band side by side, one core each (the upper in a
      // forked copy of this process), sharing the near field computed here on every core.
      std::shared_ptr<const BemSolver::NearCache> near = BemSolver(mesh, o.bem).near_field();
      AcousticOptions one = o;
      one.bem.threads = 1;
      const SingleThreadedBlas blas;
      const std::size_t half = (run.size() + 1) / 2;
      bem_detail::SideProcess upper(
          [&](const bem_detail::SideProcess::Emit& emit, TransferTimes& child_times) {
            BemSolver solver(mesh, one.bem, near);
            solve_groups(surface, bank, elements, mesh, solver, run.subspan(half), one, modes,
                         coeffs, &child_times,
                         [&](std::size_t i) { emit(i, modes[i], coeffs[i]); });
          },
          [&](std::size_t i, const ModeTransfer& t, std::vector<cd>&& a) {
            modes[i] = t;
            coeffs[i] = std::move(a);
            if (done) done();
          });
      BemSolver solver(mesh, one.bem, near);
      solve_groups(surface, bank, elements, mesh, solver, run.first(half), one, modes, coeffs,
                   times, tick);
      upper.finish(times);
    }
    l0 = l1;
  }
}

}  // namespace chladni::precompute
