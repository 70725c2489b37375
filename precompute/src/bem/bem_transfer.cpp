// Acoustic transfer by boundary elements: per mode the Burton-Miller solve on the surface, the
// multipole coefficients by quadrature, the expansion's truncation check and an interior
// null-field check of the surface solution.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>

#include "../timing.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"

namespace chladni::precompute {
namespace {

using cd = std::complex<double>;

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

}  // namespace

int bem_level(const RadiatingSurface& surface, double k, const AcousticOptions& o) {
  const double target = 2 * std::numbers::pi / o.bem_elements_per_wavelength;
  double n = double(surface.mesh().triangles.size()), h = surface.mean_element_size();
  const bool forced = o.method == AcousticOptions::Method::Bem;
  const double cap = double(forced ? o.bem_max_elements : o.bem_auto_elements);
  int fits = -1;
  for (int level = 0; level <= 4 && n <= cap; ++level, n *= 4, h /= 2) {
    fits = level;
    if (h * k <= target) return level;
  }
  return forced ? std::max(fits, 0) : -1;
}

AcousticOptions::Method resolve_method(const RadiatingSurface& surface, double k,
                                       const AcousticOptions& o) {
  using M = AcousticOptions::Method;
  if (o.method != M::Auto) return o.method;
  return bem_level(surface, k, o) >= 0 ? M::Bem : M::Sources;
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
  // field of piecewise-constant data is not meant to be accurate).
  std::vector<Vec3> inside;
  const double clearance = 1.5 * mesh.mean_size();
  for (const Vec3& x : surface.interior_points(64, clearance)) {
    bool clear = true;
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

void compute_transfer_bem(const RadiatingSurface& surface, const Soundbank& bank,
                          const std::vector<std::size_t>& which, const AcousticOptions& o,
                          std::vector<ModeTransfer>& modes, std::vector<std::vector<cd>>& coeffs,
                          TransferTimes* times, const std::function<void()>& done) {
  if (which.empty()) return;
  const std::size_t nv = bank.vertices.size();
  // One element mesh (and solver, whose LU nearby frequencies share) per refinement level, built
  // as the ascending frequencies first need it.
  std::unique_ptr<BemSurface> elements;
  std::unique_ptr<BemMesh> mesh;
  std::unique_ptr<BemSolver> solver;
  auto wavenumber = [&](std::size_t i) { return bank.damped_omega(i) / o.sound_speed; };
  for (std::size_t g0 = 0; g0 < which.size();) {
    // Modes within bem_shared_frequency of the group's first (degenerate pairs and clusters of
    // a symmetric body) share one assembly and factorization at their mean wavenumber.
    const double k0 = wavenumber(which[g0]);
    const int level = std::max(0, bem_level(surface, k0, o));
    std::size_t g1 = g0 + 1;
    double ksum = k0;
    while (g1 < which.size() &&
           std::abs(wavenumber(which[g1]) / k0 - 1) <= o.bem_shared_frequency &&
           std::max(0, bem_level(surface, wavenumber(which[g1]), o)) == level)
      ksum += wavenumber(which[g1++]);
    const double k = ksum / double(g1 - g0);
    if (!elements || elements->level != level) {
      solver.reset();
      mesh.reset();
      elements = std::make_unique<BemSurface>(surface.mesh(), level);
      mesh = std::make_unique<BemMesh>(elements->mesh);
      solver = std::make_unique<BemSolver>(*mesh, o.bem);
    }
    std::vector<NormalVelocity> un;
    std::vector<std::vector<cd>*> a;
    for (std::size_t g = g0; g < g1; ++g) {
      const std::size_t i = which[g];
      un.push_back(
          surface.from_mode_shape(bank.shapes.data() + i * nv * 3, wavenumber(i) * o.sound_speed));
      a.push_back(&coeffs[i]);
    }
    const std::vector<ModeTransfer> mt =
        bem_transfer(surface, *elements, *mesh, *solver, k, un, o, a, times);
    for (std::size_t g = g0; g < g1; ++g) {
      modes[which[g]] = mt[g - g0];
      if (done) done();
    }
    g0 = g1;
  }
}

}  // namespace chladni::precompute
