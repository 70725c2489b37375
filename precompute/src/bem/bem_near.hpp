#pragma once
// The near field of the Burton-Miller system, shared by the dense and the hierarchical solvers:
// the frequency-independent static integrals over near elements (computed once per mesh, as
// corrections to the centroid rule), and per frequency each row's near corrections and its
// closed-form self term. Internal to the BEM files.
#include <complex>
#include <cstdint>
#include <vector>

#include "bem_kernels.hpp"
#include "chladni/precompute/bem.hpp"

namespace chladni::precompute {

// For each collocation point the static integrals over the elements closer than far_ratio sizes
// (adaptive near the point), and the sum of the static hypersingular entries of its row (for the
// singularity subtraction in self_terms).
struct BemSolver::NearCache {
  // Static integral minus its centroid-rule value (what far_row adds), for each kernel; `close`:
  // within near_ratio sizes, where the dynamic remainder needs 3 points as well.
  struct Entry {
    uint32_t j;
    bool close;
    double single, dbl, adjoint, hyper;
  };
  std::vector<std::vector<Entry>> rows;
  std::vector<double> static_sum;
  bem_detail::FarGeometry far;

  NearCache(const BemMesh& m, const BemOptions& o);
};

namespace bem_detail {

using cd = std::complex<double>;

// Row i's near corrections at wavenumber k (coupling alpha): emit(j, da, db) for each cached
// near element j, where da is added to the matrix entry A_ij (-K - alpha D) and db to the
// right-hand-side weight B_ij (S + alpha K') that the centroid rule gave. The centroid rule gave
// static + dynamic: the static correction is added, and close by the 3-point dynamic remainder
// replaces the centroid one.
template <class Emit>
void near_row(const BemMesh& m, const BemSolver::NearCache& cache, double k, cd alpha,
              std::size_t i, Emit&& emit) {
  const Vec3 &x = m.centroid[i], &nx = m.normal[i];
  for (const auto& e : cache.rows[i]) {
    cd acc[5] = {e.single, e.dbl, e.adjoint, e.hyper, 0.0};
    if (e.close) {
      const auto& t = m.triangles[e.j];
      const Rule& r = rule(3);
      for (int p = 0; p < r.n; ++p)
        add_dynamic(x, nx,
                    barycentric(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]], r.b[p]),
                    m.normal[e.j], k, r.w[p] * m.area[e.j], acc);
      add_dynamic(x, nx, m.centroid[e.j], m.normal[e.j], k, -m.area[e.j], acc);
    }
    emit(e.j, -acc[1] - alpha * acc[3], acc[0] + alpha * acc[2]);
  }
}

// Row i's diagonal A_ii and right-hand-side weight B_ii (without the -alpha/2 jump term).
// Singularity subtraction: the static hypersingular operator maps a constant density to 0 on a
// closed surface (the Laplace double layer of a constant is piecewise constant), so its diagonal
// is minus the sum of the row's other static entries. This removes the O(h) error flat elements
// make on curved surfaces; only the weakly singular dynamic part of the self term comes from the
// closed form.
struct SelfTerms {
  cd a, b;
};
SelfTerms self_terms(const BemMesh& m, const BemSolver::NearCache& cache, double k, cd alpha,
                     const BemOptions& o, std::size_t i);

// The Burton-Miller coupling i/k, but no larger than i h (h: the mean element size). Any coupling
// with a positive imaginary part makes the solution unique; the hypersingular equation's
// discretization on flat elements is only first order in h, and weighting it by h keeps the
// combination second order (on a sphere at ka = 0.1: 21 % error with i/k, 0.3 % with i h).
inline cd coupling(const BemMesh& m, double k, const BemOptions& o) {
  return cd(0.0, std::min(1.0 / k, o.coupling_scale * m.mean_size()));
}

}  // namespace bem_detail
}  // namespace chladni::precompute
