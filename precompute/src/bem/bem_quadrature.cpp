// Element integrals of the Burton-Miller kernels: closed-form radial parts on the element itself,
// adaptive subdivision near it, fixed rules far from it.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "bem_kernels.hpp"
#include "chladni/core/error.hpp"
#include "chladni/precompute/bem.hpp"

namespace chladni::precompute {
namespace {

using namespace bem_detail;

// Gauss-Legendre nodes and weights on [0, 1] (Newton on P_n from the Chebyshev guesses).
struct GaussLegendre {
  static constexpr int n = 16;
  std::array<double, n> x{}, w{};
  GaussLegendre() {
    for (int i = 0; i < n; ++i) {
      double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5)), dp = 1;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1, p1 = z;
        for (int l = 2; l <= n; ++l) {
          const double p2 = ((2 * l - 1) * z * p1 - (l - 1) * p0) / l;
          p0 = p1, p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        const double dz = p1 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-16) break;
      }
      x[i] = 0.5 * (1 - z);
      w[i] = 1.0 / ((1 - z * z) * dp * dp);  // (2 / ((1-z^2) P'^2)) / 2 on [0, 1]
    }
  }
};

// Self term at the centroid x of a flat triangle, in polar coordinates (R, t) about x. With
// rho(t) the distance to the boundary: int G = 1/(4 pi) int_t int_0^rho e^(ikR) dR dt and
// FP int d2G/dn dn = 1/(4 pi) int_t FP int_0^rho e^(ikR)(1 - ikR)/R^2 dR dt
//                  = 1/(4 pi) int_t [ik - e^(ik rho)/rho] dt  (antiderivative -e^(ikR)/R).
// dG/dn_y and dG/dn_x vanish on the plane.
ElementIntegrals self_integrals(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n,
                                double k) {
  static const GaussLegendre gl;
  const Vec3 x = scale(add(add(a, b), c), 1.0 / 3);
  Vec3 e1 = sub(a, x);
  e1 = scale(e1, 1.0 / norm(e1));
  const Vec3 e2 = cross(n, e1);
  const std::array<Vec3, 3> corner{sub(a, x), sub(b, x), sub(c, x)};
  cd single = 0, hyper = 0;
  double hyper0 = 0;
  for (int e = 0; e < 3; ++e) {
    const Vec3 &p = corner[e], &q = corner[(e + 1) % 3];
    double t0 = std::atan2(dot(p, e2), dot(p, e1)), t1 = std::atan2(dot(q, e2), dot(q, e1));
    if (t1 < t0) t1 += 2 * std::numbers::pi;
    // Unit in-plane normal of the edge line pointing away from x, and the line's distance h.
    const Vec3 d = sub(q, p);
    Vec3 m = sub(p, scale(d, dot(p, d) / dot(d, d)));
    const double h = norm(m);
    m = scale(m, 1.0 / h);
    const double mu = dot(m, e1), mv = dot(m, e2);
    for (int i = 0; i < gl.n; ++i) {
      const double t = t0 + (t1 - t0) * gl.x[i], wt = (t1 - t0) * gl.w[i];
      const double rho = h / (std::cos(t) * mu + std::sin(t) * mv);
      const double kr = k * rho;
      // (e^(ik rho) - 1) / (ik) without cancellation; rho at k = 0.
      const cd radial =
          k > 0 ? cd(std::sin(kr) / k, 2 * std::pow(std::sin(0.5 * kr), 2) / k) : cd(rho, 0.0);
      single += wt * radial;
      hyper += wt * (cd(0, k) - cd(std::cos(kr), std::sin(kr)) / rho);
      hyper0 -= wt / rho;
    }
  }
  const double f = 1.0 / (4 * std::numbers::pi);
  return {single * f, 0.0, 0.0, hyper * f, hyper0 * f};
}

struct Adaptive {
  const Vec3& x;
  const Vec3& nx;
  const Vec3& ny;
  double k, ratio;
  int max_depth;
  cd acc[5] = {0, 0, 0, 0, 0};

  void run(const Vec3& a, const Vec3& b, const Vec3& c, double area, int depth) {
    const Vec3 g = scale(add(add(a, b), c), 1.0 / 3);
    const double diam = std::sqrt(std::max(
        {dot(sub(a, b), sub(a, b)), dot(sub(b, c), sub(b, c)), dot(sub(c, a), sub(c, a))}));
    const double dist = norm(sub(x, g));
    if (depth < max_depth && diam > ratio * dist) {
      const Vec3 ab = scale(add(a, b), 0.5), bc = scale(add(b, c), 0.5), ca = scale(add(c, a), 0.5);
      const double q = 0.25 * area;
      run(a, ab, ca, q, depth + 1), run(ab, b, bc, q, depth + 1);
      run(ca, bc, c, q, depth + 1), run(ab, bc, ca, q, depth + 1);
      return;
    }
    const Rule& r = rule(7);
    for (int i = 0; i < r.n; ++i)
      add_kernels(x, nx, barycentric(a, b, c, r.b[i]), ny, k, r.w[i] * area, acc);
  }
};

}  // namespace

BemMesh::BemMesh(const SurfaceMesh& mesh) : vertices(mesh.vertices), triangles(mesh.triangles) {
  const std::size_t n = triangles.size();
  centroid.resize(n), normal.resize(n), area.resize(n), size.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    for (uint32_t v : triangles[t]) {
      if (v >= vertices.size())
        throw InputError("boundary mesh: triangle " + std::to_string(t) + " has a bad index");
    }
    const Vec3 &a = vertices[triangles[t][0]], &b = vertices[triangles[t][1]],
               &c = vertices[triangles[t][2]];
    const Vec3 n2 = triangle_normal(a, b, c);
    const double len = norm(n2);
    if (!(len > 0) || !std::isfinite(len))
      throw InputError("boundary mesh: triangle " + std::to_string(t) + " is degenerate");
    area[t] = 0.5 * len;
    normal[t] = scale(n2, 1.0 / len);
    centroid[t] = scale(add(add(a, b), c), 1.0 / 3);
    size[t] = std::sqrt(std::max(
        {dot(sub(a, b), sub(a, b)), dot(sub(b, c), sub(b, c)), dot(sub(c, a), sub(c, a))}));
  }
}

double BemMesh::mean_size() const {
  double s = 0;
  for (double v : size) s += v;
  return size.empty() ? 0.0 : s / double(size.size());
}

void BemOptions::validate() const {
  auto bad = [](const char* what) { throw InputError(std::string("bem: ") + what); };
  if (!(far_ratio > near_ratio) || !(near_ratio > 0) || !std::isfinite(far_ratio))
    bad("need 0 < near ratio < far ratio");
  if (!(subdivision > 0 && subdivision <= 1)) bad("subdivision must lie in (0, 1]");
  if (!(coupling_scale > 0) || !std::isfinite(coupling_scale)) bad("coupling scale must be > 0");
  if (max_depth < 0 || max_depth > 16) bad("max depth must lie in [0, 16]");
  if (!(gmres_tolerance > 0 && gmres_tolerance < 1)) bad("GMRES tolerance must lie in (0, 1)");
  if (gmres_restart < 2 || gmres_max_iterations < 1) bad("GMRES restart >= 2, iterations >= 1");
  if (!(refactor_phase >= 0) || !std::isfinite(refactor_phase)) bad("refactor phase must be >= 0");
  if (!(hmatrix_epsilon > 0 && hmatrix_epsilon < 0.1)) bad("H-matrix epsilon must lie in (0, 0.1)");
  if (!(hmatrix_lu_epsilon >= hmatrix_epsilon && hmatrix_lu_epsilon < 0.5))
    bad("H-matrix LU epsilon must lie in [epsilon, 0.5)");
}

ElementIntegrals element_integrals(const BemMesh& m, uint32_t j, const Vec3& x, const Vec3& nx,
                                   double k, const BemOptions& o) {
  const auto& t = m.triangles[j];
  const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
  const Vec3 d = sub(x, m.centroid[j]);
  const double dist = norm(d);
  if (dist <= 1e-12 * m.size[j]) return self_integrals(a, b, c, m.normal[j], k);
  cd acc[5] = {0, 0, 0, 0, 0};
  if (dist > o.near_ratio * m.size[j]) {
    const Rule& r = rule(dist > o.far_ratio * m.size[j] ? 1 : 3);
    for (int i = 0; i < r.n; ++i)
      add_kernels(x, nx, barycentric(a, b, c, r.b[i]), m.normal[j], k, r.w[i] * m.area[j], acc);
    return {acc[0], acc[1], acc[2], acc[3], acc[4].real()};
  }
  Adaptive ad{x, nx, m.normal[j], k, o.subdivision, o.max_depth};
  ad.run(a, b, c, m.area[j], 0);
  return {ad.acc[0], ad.acc[1], ad.acc[2], ad.acc[3], ad.acc[4].real()};
}

}  // namespace chladni::precompute
