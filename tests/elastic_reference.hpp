#pragma once
// Independent references for the FEM accuracy tests: Timoshenko beam frequencies (a fine 1D
// finite-element solution) and Lamb's free-sphere frequencies (root finding on the exact
// frequency equations).
#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

namespace chladni::test {

/// Free-free Timoshenko beam: the first `count` non-zero frequencies (Hz) for bending with
/// second moment I, area A, shear coefficient kappa. Linear elements with one-point shear
/// integration (no locking), `elements` of them: converges as h^2, so 600 give ~1e-6.
inline std::vector<double> timoshenko_free_free(double L, double E, double nu, double rho, double A,
                                                double I, double kappa, int count,
                                                int elements = 600) {
  const int n = 2 * (elements + 1);  // (w, theta) per node
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n), M = Eigen::MatrixXd::Zero(n, n);
  const double h = L / elements, G = E / (2 * (1 + nu));
  for (int e = 0; e < elements; ++e) {
    const int d[4] = {2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3};  // w1 t1 w2 t2
    // bending: E I / h (t2 - t1)^2 ; shear: kappa G A h (gamma)^2, gamma = (w2-w1)/h - (t1+t2)/2
    const double kb = E * I / h;
    const double bt[4] = {0, -1, 0, 1};
    const double bs[4] = {-1 / h, -0.5, 1 / h, -0.5};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        K(d[i], d[j]) += kb * bt[i] * bt[j] + kappa * G * A * h * bs[i] * bs[j];
    // consistent mass: rho A for w, rho I for theta, linear shape functions
    for (int c = 0; c < 2; ++c) {
      const double m = (c == 0 ? rho * A : rho * I) * h / 6;
      M(d[c], d[c]) += 2 * m, M(d[2 + c], d[2 + c]) += 2 * m;
      M(d[c], d[2 + c]) += m, M(d[2 + c], d[c]) += m;
    }
  }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K, M);
  std::vector<double> f;
  for (int i = 2; i < 2 + count; ++i)  // two rigid modes first
    f.push_back(std::sqrt(es.eigenvalues()(i)) / (2 * std::numbers::pi));
  return f;
}

/// Cowper's shear coefficient of a rectangular section.
inline double cowper_rectangle(double nu) {
  return 10 * (1 + nu) / (12 + 11 * nu);
}

/// Roots of f on (lo, hi), found by scanning and bisection.
inline std::vector<double> roots(const std::function<double(double)>& f, double lo, double hi,
                                 double step = 1e-3) {
  std::vector<double> out;
  double a = lo, fa = f(a);
  for (double b = lo + step; b <= hi; b += step) {
    const double fb = f(b);
    if (std::isfinite(fa) && std::isfinite(fb) && (fa < 0) != (fb < 0)) {
      double x0 = a, x1 = b, f0 = fa;
      for (int it = 0; it < 100; ++it) {
        const double xm = 0.5 * (x0 + x1), fm = f(xm);
        if ((fm < 0) == (f0 < 0))
          x0 = xm, f0 = fm;
        else
          x1 = xm;
      }
      const double x = 0.5 * (x0 + x1);
      if (std::abs(f(x)) < 1e-6 * (std::abs(fa) + std::abs(fb))) out.push_back(x);  // not a pole
    }
    a = b, fa = fb;
  }
  return out;
}

/// Torsional modes of a free sphere, order n: (n - 1) j_n(x) - x j_(n+1)(x) = 0, x = omega a / c_s.
inline std::vector<double> lamb_torsional(int n, double hi) {
  return roots(
      [n](double x) { return (n - 1) * std::sph_bessel(n, x) - x * std::sph_bessel(n + 1, x); },
      0.05, hi);
}

/// Spheroidal modes of a free sphere, order n >= 1 (Lamb 1882 in Sato & Usami's 1962 form):
/// det [[a, b], [c, d]] = 0 with x = omega a / c_l, y = omega a / c_s. Returns the roots in y.
inline std::vector<double> lamb_spheroidal(int n, double nu, double hi) {
  const double ratio = std::sqrt((1 - 2 * nu) / (2 * (1 - nu)));  // c_s / c_l
  auto J = [](double order, double z) { return std::cyl_bessel_j(order, z); };
  auto det = [=](double y) {
    const double x = ratio * y, m = n + 0.5;
    const double a = (0.5 - n * (n - 1) / (y * y)) * J(m, x) - (2 * x / (y * y)) * J(m + 1, x);
    const double b =
        -2.0 * n * (n + 1) * (((n - 1) / (y * y)) * J(m, x) - (x / (y * y)) * J(m + 1, x));
    const double c = ((n - 1) / (y * y)) * J(m, y) - (1 / y) * J(m + 1, y);
    const double d = (2 / y) * J(m + 1, y) + (2.0 * (n * n - 1) / (y * y) - 1) * J(m, y);
    return a * d - b * c;
  };
  return roots(det, 0.05, hi);
}

}  // namespace chladni::test
