// The multipole expansion of a mode's field about the surface's centre: from equivalent
// sources by the addition theorem, trimmed to the orders that matter at 2R and checked there
// against the direct field (also used by the boundary-element path).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "../timing.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"

namespace chladni::precompute {
namespace {

using cd = std::complex<double>;

std::vector<Vec3> fibonacci_sphere(std::size_t n, double radius) {
  std::vector<Vec3> out(n);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (std::size_t i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / double(n);
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * double(i);
    out[i] = {radius * rho * std::cos(phi), radius * rho * std::sin(phi), radius * z};
  }
  return out;
}

}  // namespace

int expansion_order(double k, double radius, const AcousticOptions& o) {
  if (o.order > 0) return o.order;
  const double kr = k * radius;
  // In double first: a huge kR (a typo in --freq or --scale) must not overflow the int.
  return static_cast<int>(std::min(std::ceil(kr + 2.0 * std::cbrt(kr)) + 8, double(o.max_order)));
}

ModeTransfer expand_sources(const RadiatingSurface& surface, const SourceFit& fit,
                            const AcousticOptions& o, TransferKernels& kernels, std::vector<cd>& a,
                            TransferTimes* times) {
  const auto t0 = std::chrono::steady_clock::now();
  const double k = fit.k, R = surface.radius();
  double rs_max = 0;
  for (const Vec3& y : fit.sources) rs_max = std::max(rs_max, std::sqrt(dot(y, y)));
  const int L = expansion_order(k, rs_max, o);
  const std::size_t nlm = sh_count(L);

  // c_lm = i k sum_s q_s j_l(k r_s) Y_lm(y_s); a_lm = c_lm h_l(k R).
  std::vector<cd> h(static_cast<std::size_t>(L) + 1);
  sph_hankel1(L, k * R, h.data());
  std::vector<double> j(static_cast<std::size_t>(L) + 1), y(nlm);
  a.assign(nlm, cd(0.0));
  for (std::size_t s = 0; s < fit.sources.size(); ++s) {
    const Vec3& ys = fit.sources[s];
    sph_bessel_j(L, k * std::sqrt(dot(ys, ys)), j.data());
    real_sh(L, ys, y.data());
    const cd qs = cd(0.0, k) * fit.strength[s];
    for (int l = 0; l <= L; ++l) {
      const cd f = qs * j[l] * h[l];
      for (int m = -l; m <= l; ++m) a[sh_index(l, m)] += f * y[sh_index(l, m)];
    }
  }
  ModeTransfer mt =
      finish_expansion(surface, k, L, a, o, [&](const std::vector<Vec3>& pts, cd* out) {
        kernels.field(pts, fit.sources, fit.strength, k, out);
      });
  mt.sources = static_cast<uint32_t>(fit.sources.size());
  mt.fit_residual = static_cast<float>(fit.residual);
  mt.held_out_error = static_cast<float>(fit.held_out);
  if (times) times->expand += seconds_since(t0);
  return mt;
}

ModeTransfer finish_expansion(const RadiatingSurface& surface, double k, int L, std::vector<cd>& a,
                              const AcousticOptions& o,
                              const std::function<void(const std::vector<Vec3>&, cd*)>& direct,
                              std::size_t max_check) {
  const double R = surface.radius();
  // Trim the orders that carry (almost) nothing at 2R.
  std::vector<cd> ratio(static_cast<std::size_t>(L) + 1);
  sph_hankel1_ratio(L, 2.0 * k * R, k * R, ratio.data());
  std::vector<double> energy(static_cast<std::size_t>(L) + 1, 0.0);
  double total = 0;
  for (int l = 0; l <= L; ++l) {
    for (int m = -l; m <= l; ++m) energy[l] += std::norm(a[sh_index(l, m)]);
    energy[l] *= std::norm(ratio[l]);
    total += energy[l];
  }
  int keep = L;
  if (o.order == 0) {
    double tail = 0;
    while (keep > 0 && tail + energy[keep] <= o.truncation * o.truncation * total)
      tail += energy[keep--];
  }
  a.resize(sh_count(keep));

  ModeTransfer mt;
  mt.wavenumber = k;
  mt.order = static_cast<uint32_t>(keep);

  // Check against the direct field on the sphere of radius 2R.
  const std::size_t nchk =
      std::clamp<std::size_t>(2 * sh_count(keep), 64, std::max<std::size_t>(max_check, 64));
  const std::vector<Vec3> pts = fibonacci_sphere(nchk, 2.0 * R);
  std::vector<cd> ref(nchk);
  direct(pts, ref.data());
  std::vector<cd> rr(static_cast<std::size_t>(keep) + 1);
  sph_hankel1_ratio(keep, 2.0 * k * R, k * R, rr.data());
  std::vector<double> yy(sh_count(keep));
  double num = 0, den = 0;
  for (std::size_t i = 0; i < nchk; ++i) {
    real_sh(keep, pts[i], yy.data());
    cd p = 0.0;
    for (int l = 0; l <= keep; ++l) {
      cd sl = 0.0;
      for (int m = -l; m <= l; ++m) sl += a[sh_index(l, m)] * yy[sh_index(l, m)];
      p += rr[l] * sl;
    }
    num += std::norm(p - ref[i]);
    den += std::norm(ref[i]);
  }
  mt.expansion_error = den > 0 ? static_cast<float>(std::sqrt(num / den)) : 0.0f;
  return mt;
}

}  // namespace chladni::precompute
