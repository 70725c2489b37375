#include "chladni/precompute/velocity_pattern.hpp"

#include <algorithm>
#include <cmath>

#include "chladni/core/error.hpp"

namespace chladni::precompute {
namespace {

Vec3 area_centroid(const SurfaceMesh& mesh) {
  Vec3 c{0, 0, 0};
  double area = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3 n = triangle_normal(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
    const double a = 0.5 * std::sqrt(dot(n, n));
    for (int k = 0; k < 3; ++k)
      c[k] += a * (mesh.vertices[t[0]][k] + mesh.vertices[t[1]][k] + mesh.vertices[t[2]][k]) / 3;
    area += a;
  }
  if (area > 0)
    for (double& x : c) x /= area;
  return c;
}

}  // namespace

std::vector<std::complex<double>> harmonic_velocity(const SurfaceMesh& mesh, int l, int m,
                                                    double amplitude) {
  if (l < 0 || l > 40 || std::abs(m) > l)
    throw InputError("a spherical harmonic needs integers 0 <= l <= 40 and |m| <= l");
  const Vec3 c = area_centroid(mesh);
  std::vector<std::complex<double>> out(mesh.vertices.size());
  for (std::size_t v = 0; v < out.size(); ++v) {
    const Vec3 d = sub(mesh.vertices[v], c);
    const double r = std::sqrt(dot(d, d));
    const double theta = r > 0 ? std::acos(std::clamp(d[2] / r, -1.0, 1.0)) : 0.0;
    const double phi = std::atan2(d[1], d[0]);
    const double p = std::assoc_legendre(unsigned(l), unsigned(std::abs(m)), std::cos(theta));
    out[v] = amplitude * p * (m >= 0 ? std::cos(m * phi) : std::sin(-m * phi));
  }
  return out;
}

std::vector<std::complex<double>> uniform_velocity(const SurfaceMesh& mesh, double amplitude) {
  return std::vector<std::complex<double>>(mesh.vertices.size(), amplitude);
}

}  // namespace chladni::precompute
