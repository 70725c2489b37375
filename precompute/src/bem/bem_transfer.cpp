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

ModeTransfer bem_transfer(const RadiatingSurface& surface, const BemSurface& elements,
                          const BemMesh& mesh, BemSolver& solver, double k,
                          const NormalVelocity& un, const AcousticOptions& o, std::vector<cd>& a,
                          TransferTimes* times, std::vector<cd>* pressure, std::vector<cd>* dpdn) {
  const std::size_t n = mesh.elements();
  if (n != elements.parent.size())
    throw InternalError("bem: the boundary mesh is not the surface's elements");
  // dp/dn = i omega rho0 u_n, averaged over each element (3 points, mapped into the parent).
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
  const BemSolver::Times before = solver.times();
  const BemSolver::Result res = solver.solve(k, q);
  if (times) {
    const BemSolver::Times& after = solver.times();
    times->matrix += after.assembly - before.assembly;
    times->solve += after.factorization - before.factorization + after.iteration - before.iteration;
  }

  const auto t0 = std::chrono::steady_clock::now();
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
  if (times) times->expand += seconds_since(t0);
  if (pressure) *pressure = res.pressure;
  if (dpdn) *dpdn = std::move(q);
  return mt;
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
  for (std::size_t i : which) {
    const double omega = bank.damped_omega(i);  // radiates at the damped frequency
    const double k = omega / o.sound_speed;
    const int level = std::max(0, bem_level(surface, k, o));
    if (!elements || elements->level != level) {
      solver.reset();
      mesh.reset();
      elements = std::make_unique<BemSurface>(surface.mesh(), level);
      mesh = std::make_unique<BemMesh>(elements->mesh);
      solver = std::make_unique<BemSolver>(*mesh, o.bem);
    }
    const NormalVelocity un = surface.from_mode_shape(bank.shapes.data() + i * nv * 3, omega);
    modes[i] = bem_transfer(surface, *elements, *mesh, *solver, k, un, o, coeffs[i], times);
    if (done) done();
  }
}

}  // namespace chladni::precompute
