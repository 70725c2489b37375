// From the surface pressure and its normal derivative to the field: the Kirchhoff-Helmholtz
// representation at points, and its far-field multipole coefficients by quadrature.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <thread>

#include "../parallel.hpp"
#include "bem_kernels.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/precompute/bem.hpp"

namespace chladni::precompute {

std::vector<cd> bem_field(const BemMesh& m, double k, std::span<const cd> p, std::span<const cd> q,
                          std::span<const Vec3> points, const BemOptions& o) {
  const std::size_t n = m.elements();
  if (p.size() != n || q.size() != n) throw InternalError("bem: surface data per element expected");
  std::vector<cd> out(points.size());
  const Vec3 none{0, 0, 0};
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!is_finite(points[i]))
      throw InputError("field point " + std::to_string(i) + " is not finite");
  }
  parallel_for(points.size(), o.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      cd sum = 0;
      for (std::size_t j = 0; j < n; ++j) {
        const ElementIntegrals ei = element_integrals(m, uint32_t(j), points[i], none, k, o);
        sum += p[j] * ei.dbl - q[j] * ei.single;
      }
      out[i] = sum;
    }
  });
  return out;
}

// Exterior addition theorem for real harmonics: G(x, y) = i k sum_lm j_l(k|y|) Y_lm(y) h_l(k|x|)
// Y_lm(x) for |x| > |y| (about the centre), so the representation p = int p dG/dn_y - q G gives
// c_lm = i k int [p d/dn_y (j_l Y_lm)(y) - q j_l Y_lm(y)]. The normal derivative of the regular
// wave is a central difference (step 1e-6 of the wavelength or the radius, whichever is smaller:
// error ~1e-12 relative, round-off ~1e-10).
std::vector<cd> bem_multipoles(const BemMesh& m, double k, const Vec3& centre, int L,
                               std::span<const cd> p, std::span<const cd> q, int threads) {
  using namespace bem_detail;
  const std::size_t n = m.elements(), nlm = sh_count(L);
  if (p.size() != n || q.size() != n) throw InternalError("bem: surface data per element expected");
  double rmax = 0;
  for (const Vec3& v : m.vertices) rmax = std::max(rmax, norm(sub(v, centre)));
  const double step = 1e-6 * std::min(rmax > 0 ? rmax : 1.0, 2 * std::numbers::pi / k);
  const Rule& r = rule(3);
  const std::size_t hw = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t nt = std::min<std::size_t>(threads > 0 ? std::size_t(threads) : hw,
                                               std::max<std::size_t>(1, n / 64));
  std::vector<std::vector<cd>> part(nt, std::vector<cd>(nlm, cd(0.0)));
  parallel_for(nt, int(nt), [&](std::size_t t0, std::size_t t1) {
    std::vector<double> jl(std::size_t(L) + 1), y(nlm), jp(std::size_t(L) + 1), yp(nlm),
        jm(std::size_t(L) + 1), ym(nlm);
    for (std::size_t t = t0; t < t1; ++t) {
      std::vector<cd>& acc = part[t];
      for (std::size_t j = n * t / nt; j < n * (t + 1) / nt; ++j) {
        const auto& tri = m.triangles[j];
        const Vec3& nj = m.normal[j];
        for (int i = 0; i < r.n; ++i) {
          const Vec3 pt =
              sub(barycentric(m.vertices[tri[0]], m.vertices[tri[1]], m.vertices[tri[2]], r.b[i]),
                  centre);
          const Vec3 pp = add(pt, scale(nj, step)), pm = sub(pt, scale(nj, step));
          sph_bessel_j(L, k * norm(pt), jl.data());
          real_sh(L, pt, y.data());
          sph_bessel_j(L, k * norm(pp), jp.data());
          real_sh(L, pp, yp.data());
          sph_bessel_j(L, k * norm(pm), jm.data());
          real_sh(L, pm, ym.data());
          const double w = r.w[i] * m.area[j];
          const cd pw = p[j] * (w / (2 * step)), qw = q[j] * w;
          for (int l = 0; l <= L; ++l) {
            for (int mm = -l; mm <= l; ++mm) {
              const std::size_t s = sh_index(l, mm);
              acc[s] += pw * (jp[l] * yp[s] - jm[l] * ym[s]) - qw * (jl[l] * y[s]);
            }
          }
        }
      }
    }
  });
  std::vector<cd> c(nlm, cd(0.0));
  for (const auto& pt : part)
    for (std::size_t s = 0; s < nlm; ++s) c[s] += pt[s];
  for (cd& v : c) v *= cd(0.0, k);
  return c;
}

}  // namespace chladni::precompute
