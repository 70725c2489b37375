// GMRES(m) with Givens rotations and modified Gram-Schmidt (Saad & Schultz 1986), right
// preconditioned so the residual it monitors is the true one.
#include "bem_gmres.hpp"

#include <Eigen/Dense>
#include <cmath>

namespace chladni::precompute::bem_detail {

using cd = std::complex<double>;

double norm2(const std::vector<cd>& v) {
  double s = 0;
  for (const cd& z : v) s += std::norm(z);
  return std::sqrt(s);
}

int gmres(const MatVec& apply, const Precondition& precondition, const std::vector<cd>& b,
          const BemOptions& o, std::size_t pad, std::vector<cd>& x) {
  const std::size_t n = b.size();
  const double nb = norm2(b);
  const int m = o.gmres_restart;
  std::vector<std::vector<cd>> V(std::size_t(m) + 1, std::vector<cd>(n + pad));
  Eigen::MatrixXcd H = Eigen::MatrixXcd::Zero(m + 1, m);
  std::vector<cd> r(n + pad), w(n + pad), g(std::size_t(m) + 1);
  std::vector<cd> cs(static_cast<std::size_t>(m)), sn(static_cast<std::size_t>(m));
  std::vector<cd> xp(n + pad);
  int total = 0;
  while (total < o.gmres_max_iterations) {
    std::copy(x.begin(), x.begin() + long(n), xp.begin());
    apply(xp.data(), r.data());
    for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - r[i];
    double beta = 0;
    for (std::size_t i = 0; i < n; ++i) beta += std::norm(r[i]);
    beta = std::sqrt(beta);
    if (beta / nb <= o.gmres_tolerance) break;
    for (std::size_t i = 0; i < n; ++i) V[0][i] = r[i] / beta;
    std::fill(g.begin(), g.end(), cd(0.0));
    g[0] = beta;
    int j = 0;
    for (; j < m && total < o.gmres_max_iterations; ++j, ++total) {
      std::copy(V[j].begin(), V[j].begin() + long(n), w.begin());
      precondition(w.data());
      apply(w.data(), V[j + 1].data());
      auto& v = V[j + 1];
      for (int i = 0; i <= j; ++i) {
        cd h = 0;
        for (std::size_t e = 0; e < n; ++e) h += std::conj(V[i][e]) * v[e];
        H(i, j) = h;
        for (std::size_t e = 0; e < n; ++e) v[e] -= h * V[i][e];
      }
      double hn = 0;
      for (std::size_t e = 0; e < n; ++e) hn += std::norm(v[e]);
      hn = std::sqrt(hn);
      H(j + 1, j) = hn;
      if (hn > 0)
        for (std::size_t e = 0; e < n; ++e) v[e] /= hn;
      for (int i = 0; i < j; ++i) {  // previous Givens rotations
        const cd t = cs[i] * H(i, j) + sn[i] * H(i + 1, j);
        H(i + 1, j) = -std::conj(sn[i]) * H(i, j) + std::conj(cs[i]) * H(i + 1, j);
        H(i, j) = t;
      }
      const double den = std::sqrt(std::norm(H(j, j)) + std::norm(H(j + 1, j)));
      cs[j] = den > 0 ? H(j, j) / den : 1.0;
      sn[j] = den > 0 ? H(j + 1, j) / den : 0.0;
      H(j, j) = den;
      H(j + 1, j) = 0;
      g[j + 1] = -std::conj(sn[j]) * g[j];
      g[j] = std::conj(cs[j]) * g[j];
      if (std::abs(g[j + 1]) / nb <= o.gmres_tolerance || hn == 0) {
        ++j, ++total;
        break;
      }
    }
    // x += M^-1 V y with H y = g (upper triangular j x j).
    Eigen::VectorXcd y(j);
    for (int i = j - 1; i >= 0; --i) {
      cd s = g[i];
      for (int c = i + 1; c < j; ++c) s -= H(i, c) * y(c);
      y(i) = s / H(i, i);
    }
    std::fill(w.begin(), w.end(), cd(0.0));
    for (int i = 0; i < j; ++i)
      for (std::size_t e = 0; e < n; ++e) w[e] += y(i) * V[i][e];
    precondition(w.data());
    for (std::size_t e = 0; e < n; ++e) x[e] += w[e];
  }
  return total;
}

}  // namespace chladni::precompute::bem_detail
