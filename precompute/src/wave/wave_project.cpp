#include "wave_project.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

#include "../parallel.hpp"

#include "chladni/core/spherical.hpp"

namespace chladni::precompute::wave {
namespace {

// A recording face's centre and outward unit normal, in the object's frame.
struct Face {
  Vec3 x, n;
};
Face record_face(const Problem& P, std::size_t f) {
  const Grid& g = P.grid;
  const uint32_t axis = P.record.axis[f];
  const uint64_t cell = P.record.cell[f];
  const uint64_t i = cell % g.n[0], j = (cell / g.n[0]) % g.n[1], k = cell / g.stride(2);
  Vec3 x = g.centre(i, j, k);
  x[axis] += 0.5 * g.h;
  return {P.to_object(x), scale(P.axis_in_object(axis), double(P.record.sign[f]))};
}

}  // namespace

Separated separate(const Problem& P, const std::vector<float>& samples,
                   const std::vector<double>& omega, double dt) {
  const std::size_t J = omega.size(), ns = P.samples(), nf = P.record.size();
  Separated s;
  s.modes = J, s.faces = nf;
  // Basis columns cos(w t), sin(w t): p is recorded at (n + 1) dt, w at (n + 1/2) dt.
  auto basis = [&](double shift) {
    Eigen::MatrixXd T(static_cast<Eigen::Index>(ns), static_cast<Eigen::Index>(2 * J));
    for (std::size_t r = 0; r < ns; ++r) {
      const double t = (double(P.first_sample + r * P.stride) + shift) * dt;
      for (std::size_t m = 0; m < J; ++m) {
        T(Eigen::Index(r), Eigen::Index(2 * m)) = std::cos(omega[m] * t);
        T(Eigen::Index(r), Eigen::Index(2 * m + 1)) = std::sin(omega[m] * t);
      }
    }
    return T;
  };
  s.p.assign(J * nf, cd(0.0)), s.w.assign(J * nf, cd(0.0));
  s.error.assign(J, 0.0);
  double res2 = 0, tot2 = 0;
  std::vector<double> own(J, 0.0), var(J, 0.0);
  for (int which = 0; which < 2; ++which) {
    const Eigen::MatrixXd T = basis(which == 0 ? 1.0 : 0.5);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(T);
    const Eigen::MatrixXd cov = (T.transpose() * T).inverse();
    Eigen::MatrixXd Y(static_cast<Eigen::Index>(ns), static_cast<Eigen::Index>(nf));
    for (std::size_t r = 0; r < ns; ++r)
      for (std::size_t f = 0; f < nf; ++f)
        Y(Eigen::Index(r), Eigen::Index(f)) = samples[(r * nf + f) * 2 + std::size_t(which)];
    const Eigen::MatrixXd X = qr.solve(Y);
    const Eigen::MatrixXd R = Y - T * X;
    const double dof = std::max<double>(1.0, double(ns) - double(2 * J));
    const Eigen::VectorXd sigma2 = R.colwise().squaredNorm().transpose() / dof;
    res2 += R.squaredNorm(), tot2 += Y.squaredNorm();
    std::vector<cd>& out = which == 0 ? s.p : s.w;
    for (std::size_t m = 0; m < J; ++m) {
      const auto c = Eigen::Index(2 * m), d = c + 1;
      for (std::size_t f = 0; f < nf; ++f) {
        const auto fi = Eigen::Index(f);
        out[m * nf + f] = cd(X(c, fi), X(d, fi));
        own[m] += X(c, fi) * X(c, fi) + X(d, fi) * X(d, fi);
        var[m] += (cov(c, c) + cov(d, d)) * sigma2(fi);
      }
    }
  }
  for (std::size_t m = 0; m < J; ++m) s.error[m] = own[m] > 0 ? std::sqrt(var[m] / own[m]) : 1.0;
  s.residual = tot2 > 0 ? std::sqrt(res2 / tot2) : 0.0;
  return s;
}

std::vector<std::vector<cd>> box_multipoles(const Problem& P, const Separated& s,
                                            const std::vector<double>& k, const Vec3& centre,
                                            const std::vector<int>& L, int threads) {
  const Grid& g = P.grid;
  const std::size_t J = k.size(), nf = s.faces;
  const int Lmax = *std::max_element(L.begin(), L.end());
  const double dS = g.h * g.h, eps = 1e-3 * g.h;
  std::vector<std::vector<cd>> total(J);
  for (std::size_t m = 0; m < J; ++m) total[m].assign(sh_count(L[m]), cd(0.0));
  std::mutex mu;
  parallel_for(nf, threads, [&](std::size_t f0, std::size_t f1) {
    std::vector<std::vector<cd>> c(J);
    for (std::size_t m = 0; m < J; ++m) c[m].assign(sh_count(L[m]), cd(0.0));
    const std::size_t nlm = sh_count(Lmax);
    std::vector<double> y(nlm), yp(nlm), ym(nlm), j(std::size_t(Lmax) + 2);
    for (std::size_t f = f0; f < f1; ++f) {
      const Face face = record_face(P, f);
      const Vec3 r = sub(face.x, centre);
      const double sign = P.record.sign[f], rn = std::sqrt(dot(r, r)), cos_n = dot(face.n, r) / rn;
      const Vec3 rp = add(r, scale(face.n, eps)), rm = sub(r, scale(face.n, eps));
      real_sh(Lmax, r, y.data()), real_sh(Lmax, rp, yp.data()), real_sh(Lmax, rm, ym.data());
      for (std::size_t i = 0; i < nlm; ++i) yp[i] = (yp[i] - ym[i]) / (2 * eps);
      for (std::size_t m = 0; m < J; ++m) {
        sph_bessel_j(L[m] + 1, k[m] * rn, j.data());
        const cd pf = s.p[m * nf + f];
        const cd q = cd(0.0, k[m]) * sign * s.w[m * nf + f];  // dp/dn = i k w_n
        cd* out = c[m].data();
        for (int l = 0; l <= L[m]; ++l) {
          const double jl = j[std::size_t(l)];
          // d/dx j_l = j_(l-1) - (l+1)/x j_l, and j_0' = -j_1.
          const double djl = l == 0 ? -j[1] : j[std::size_t(l) - 1] - (l + 1) / (k[m] * rn) * jl;
          const cd radial = pf * (k[m] * djl * cos_n) - q * jl, angular = pf * jl;
          const std::size_t i0 = sh_index(l, -l), i1 = sh_index(l, l);
          for (std::size_t i = i0; i <= i1; ++i) out[i] += radial * y[i] + angular * yp[i];
        }
      }
    }
    std::lock_guard lock(mu);
    for (std::size_t m = 0; m < J; ++m)
      for (std::size_t i = 0; i < c[m].size(); ++i) total[m][i] += c[m][i];
  });
  for (std::size_t m = 0; m < J; ++m)
    for (cd& v : total[m]) v *= cd(0.0, k[m]) * dS;
  return total;
}

void box_field(const Problem& P, const Separated& s, std::size_t m, double k,
               const std::vector<Vec3>& points, cd* out, int threads) {
  const Grid& g = P.grid;
  const std::size_t nf = s.faces;
  const double dS = g.h * g.h;
  parallel_for(points.size(), threads, [&](std::size_t i0, std::size_t i1) {
    for (std::size_t i = i0; i < i1; ++i) {
      cd sum = 0;
      for (std::size_t f = 0; f < nf; ++f) {
        const Face face = record_face(P, f);
        const Vec3 d = sub(face.x, points[i]);  // y - x
        const double rho = std::sqrt(dot(d, d)), sign = P.record.sign[f];
        const cd G = std::exp(cd(0.0, k * rho)) / (4.0 * std::numbers::pi * rho);
        const cd dG = G * cd(-1.0 / rho, k) * (dot(face.n, d) / rho);  // dG/dn_y
        const cd q = cd(0.0, k) * sign * s.w[m * nf + f];
        sum += s.p[m * nf + f] * dG - q * G;
      }
      out[i] = sum * dS;
    }
  });
}

}  // namespace chladni::precompute::wave
