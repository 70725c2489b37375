#pragma once
// The four Helmholtz kernels of the Burton-Miller equation at one pair of points, and the
// triangle rules the element integrals use. Internal to the BEM files.
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <span>
#include <vector>

#include "chladni/core/vec3.hpp"
#include "chladni/precompute/bem.hpp"

namespace chladni::precompute::bem_detail {

using cd = std::complex<double>;

/// Adds w x {G, dG/dn_y, dG/dn_x, d2G/dn_x dn_y, its static (k = 0) part} at x (normal nx),
/// y (normal ny), x != y.
/// With r = x - y, R = |r|, G = e^(ikR)/(4 pi R):
///   dG/dn_y = G (1 - ikR) (r.n_y) / R^2,   dG/dn_x = -G (1 - ikR) (r.n_x) / R^2,
///   d2G/dn_x dn_y = G / R^2 [n_x.n_y (1 - ikR) - (r.n_x)(r.n_y)/R^2 (3 - 3ikR - k^2 R^2)].
template <bool with_static = true>
inline void add_kernels(const Vec3& x, const Vec3& nx, const Vec3& y, const Vec3& ny, double k,
                        double w, cd* acc) {
  const double r0 = x[0] - y[0], r1 = x[1] - y[1], r2 = x[2] - y[2];
  const double R2 = r0 * r0 + r1 * r1 + r2 * r2, R = std::sqrt(R2), inv2 = 1.0 / R2;
  const double kr = k * R;
  const double s = w / (4.0 * std::numbers::pi * R);
  const cd g(s * std::cos(kr), s * std::sin(kr));
  const double rny = r0 * ny[0] + r1 * ny[1] + r2 * ny[2];
  const double rnx = r0 * nx[0] + r1 * nx[1] + r2 * nx[2];
  const double nn = nx[0] * ny[0] + nx[1] * ny[1] + nx[2] * ny[2];
  const cd one_m(1.0, -kr);        // 1 - ikR
  const cd gp = g * one_m * inv2;  // G (1 - ikR) / R^2
  acc[0] += g;
  acc[1] += gp * rny;
  acc[2] -= gp * rnx;
  acc[3] += g * inv2 * (nn * one_m - rnx * rny * inv2 * cd(3.0 - kr * kr, -3.0 * kr));
  if constexpr (with_static) acc[4] += s * inv2 * (nn - 3.0 * rnx * rny * inv2);
}

/// Adds w x the dynamic remainders {G - G0, dG/dn_y - its static part, dG/dn_x - ..., d2G/dn dn -
/// ...} (G0 = 1/(4 pi R)): bounded or O(k^2/R), so low-order rules integrate them on near
/// elements whose static parts were integrated once, adaptively. With e = e^(ikR),
/// a = (1 - ikR) e - 1 and b = (3 - 3ikR - k^2 R^2) e - 3 (both O(k^2 R^2), written without
/// cancelling leading terms): G - G0 = (e - 1)/(4 pi R), dG/dn_y - . = a (r.n_y)/(4 pi R^3),
/// dG/dn_x - . = -a (r.n_x)/(4 pi R^3), d2G - . = [n_x.n_y a - (r.n_x)(r.n_y)/R^2 b]/(4 pi R^3).
inline void add_dynamic(const Vec3& x, const Vec3& nx, const Vec3& y, const Vec3& ny, double k,
                        double w, cd* acc) {
  const double r0 = x[0] - y[0], r1 = x[1] - y[1], r2 = x[2] - y[2];
  const double R2 = r0 * r0 + r1 * r1 + r2 * r2, R = std::sqrt(R2);
  const double kr = k * R, c = std::cos(kr), s = std::sin(kr), h = std::sin(0.5 * kr);
  const double f = w / (4.0 * std::numbers::pi * R), f3 = f / R2;
  const cd em1(-2.0 * h * h, s);                         // e - 1
  const cd a(-2.0 * h * h + kr * s, s - kr * c);         // (1 - ikR) e - 1
  const cd b(-6.0 * h * h - kr * kr * c + 3.0 * kr * s,  // (3 - 3ikR - k^2R^2) e - 3
             3.0 * (s - kr * c) - kr * kr * s);
  const double rny = r0 * ny[0] + r1 * ny[1] + r2 * ny[2];
  const double rnx = r0 * nx[0] + r1 * nx[1] + r2 * nx[2];
  const double nn = nx[0] * ny[0] + nx[1] * ny[1] + nx[2] * ny[2];
  acc[0] += f * em1;
  acc[1] += f3 * rny * a;
  acc[2] -= f3 * rnx * a;
  acc[3] += f3 * (nn * a - rnx * rny / R2 * b);
}

struct Rule {
  int n;
  std::array<std::array<double, 3>, 7> b;  // barycentric points
  std::array<double, 7> w;                 // weights summing to 1
};

/// Centroid (degree 1), three interior points (degree 2), Dunavant's 7 points (degree 5).
inline const Rule& rule(int points) {
  static const Rule one{1, {{{1.0 / 3, 1.0 / 3, 1.0 / 3}}}, {1.0}};
  static const Rule three{
      3,
      {{{2.0 / 3, 1.0 / 6, 1.0 / 6}, {1.0 / 6, 2.0 / 3, 1.0 / 6}, {1.0 / 6, 1.0 / 6, 2.0 / 3}}},
      {1.0 / 3, 1.0 / 3, 1.0 / 3}};
  constexpr double a1 = 0.059715871789770, b1 = 0.470142064105115, w1 = 0.132394152788506;
  constexpr double a2 = 0.797426985353087, b2 = 0.101286507323456, w2 = 0.125939180544827;
  static const Rule seven{7,
                          {{{1.0 / 3, 1.0 / 3, 1.0 / 3},
                            {a1, b1, b1},
                            {b1, a1, b1},
                            {b1, b1, a1},
                            {a2, b2, b2},
                            {b2, a2, b2},
                            {b2, b2, a2}}},
                          {0.225, w1, w1, w1, w2, w2, w2}};
  return points == 1 ? one : points == 3 ? three : seven;
}

inline Vec3 barycentric(const Vec3& a, const Vec3& b, const Vec3& c,
                        const std::array<double, 3>& l) {
  return {l[0] * a[0] + l[1] * b[0] + l[2] * c[0], l[0] * a[1] + l[1] * b[1] + l[2] * c[1],
          l[0] * a[2] + l[1] * b[2] + l[2] * c[2]};
}

/// Element centroids, normals and area / (4 pi) as separate arrays, for far_row.
struct FarGeometry {
  std::vector<double> cx, cy, cz, nx, ny, nz, w;
  FarGeometry() = default;
  explicit FarGeometry(const BemMesh& m) {
    for (std::size_t j = 0; j < m.elements(); ++j) {
      cx.push_back(m.centroid[j][0]), cy.push_back(m.centroid[j][1]);
      cz.push_back(m.centroid[j][2]), nx.push_back(m.normal[j][0]);
      ny.push_back(m.normal[j][1]), nz.push_back(m.normal[j][2]);
      w.push_back(m.area[j] / (4 * std::numbers::pi));
    }
  }
  /// g's elements in another order: element h here is g's order[h].
  FarGeometry(const FarGeometry& g, const int* order) {
    for (std::size_t h = 0; h < g.cx.size(); ++h) {
      const std::size_t j = std::size_t(order[h]);
      cx.push_back(g.cx[j]), cy.push_back(g.cy[j]), cz.push_back(g.cz[j]);
      nx.push_back(g.nx[j]), ny.push_back(g.ny[j]), nz.push_back(g.nz[j]), w.push_back(g.w[j]);
    }
  }
};

/// Row i of the Burton-Miller system by the centroid rule for every element (coupling a = i al):
/// the matrix entry -K - a D in (rre, rim) and the weight of dp/dn in the right-hand side,
/// S + a K', in (tre, tim). The caller overwrites the near and self entries.
void far_row(const FarGeometry& g, const Vec3& x, const Vec3& nx, double k, double al, double* rre,
             double* rim, double* tre, double* tim);

/// Right-hand sides qs[first..] as separate real and imaginary arrays, the layout far_rhs reads.
struct SplitRightHandSides {
  SplitRightHandSides(std::span<const std::vector<std::complex<double>>> qs, std::size_t first) {
    for (std::size_t v = first; v < qs.size(); ++v) {
      std::vector<double>& r = re.emplace_back(qs[v].size());
      std::vector<double>& i = im.emplace_back(qs[v].size());
      for (std::size_t j = 0; j < qs[v].size(); ++j) r[j] = qs[v][j].real(), i[j] = qs[v][j].imag();
    }
    for (std::size_t v = 0; v < re.size(); ++v)
      pre.push_back(re[v].data()), pim.push_back(im[v].data());
  }
  std::vector<std::vector<double>> re, im;
  std::vector<const double*> pre, pim;
};

/// out[v] = sum_(j != skip) (S + a K')_j q_j for each right-hand side q = qre[v] + i qim[v] by
/// the centroid rule: the far part of a row's right-hand sides without storing the row.
void far_rhs(const FarGeometry& g, const Vec3& x, const Vec3& nx, double k, double al,
             std::span<const double* const> qre, std::span<const double* const> qim,
             std::size_t skip, std::complex<double>* out);

/// Matrix entries -K - a D by the centroid rule for the pairs (row0 + r, col0 + c) of g's
/// elements into column-major (re, im) (m x n); pairs of an element with itself get meaningless
/// values, to be replaced.
void far_block(const FarGeometry& g, std::size_t row0, std::size_t m, std::size_t col0,
               std::size_t n, double k, double al, double* re, double* im);

}  // namespace chladni::precompute::bem_detail
