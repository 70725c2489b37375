// The orientations of an object on its grids (wave_transfer.hpp) and the turned surface.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "chladni/core/error.hpp"

#include "wave_grid.hpp"

namespace chladni::precompute::wave {

namespace {

// Bodies whose cos 4 phi content about the axis, and the relative difference of the two other
// principal moments, are at most this are turned (a bowl, a bell, a sphere: 0; a gear, a rotor:
// 0.01-0.02). A square bar reads 0.12 in cos 4 phi, a shaft coupling 0.09; the cow has little
// cos 4 phi content but is no body of revolution (its moments differ).
constexpr double kNearRevolution = 0.05;

struct Moments {
  int axis = 2;
  double fourfold = 0;
  double roundness = 0;  ///< |difference| / sum of the other two principal moments
};

// The principal axis of the surface's second moment (triangle centroids weighted by area) whose
// eigenvalue stands apart from the other two, snapped to the nearest coordinate axis; how far
// apart those two are; and the surface's |sum w r e^(4 i phi)| / sum w r about the axis through
// the centroid.
Moments moments(const SurfaceMesh& mesh) {
  std::vector<std::pair<Eigen::Vector3d, double>> parts;
  parts.reserve(mesh.triangles.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double area = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const double w = 0.5 * norm(cross(sub(b, a), sub(c, a)));
    const Eigen::Vector3d x((a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3,
                            (a[2] + b[2] + c[2]) / 3);
    parts.emplace_back(x, w), mean += w * x, area += w;
  }
  Moments out;
  if (!(area > 0)) return out;
  mean /= area;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (const auto& [x, w] : parts) m += w * (x - mean) * (x - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m);
  const Eigen::Vector3d l = es.eigenvalues();  // ascending
  const bool low = l[1] - l[0] > l[2] - l[1];
  const Eigen::Vector3d v = es.eigenvectors().col(low ? 0 : 2);
  const double p = low ? l[1] : l[0], q = low ? l[2] : l[1];
  out.roundness = p + q > 0 ? (q - p) / (p + q) : 0.0;
  for (int a = 0; a < 3; ++a)
    if (std::abs(v[a]) > std::abs(v[out.axis]) + 1e-9) out.axis = a;
  const int u = (out.axis + 1) % 3, w = (out.axis + 2) % 3;
  std::complex<double> sum = 0;
  double weight = 0;
  for (const auto& [x, a] : parts) {
    const double dx = x[u] - mean[u], dy = x[w] - mean[w], r = std::hypot(dx, dy);
    sum += a * r * std::exp(std::complex<double>(0.0, 4.0 * std::atan2(dy, dx)));
    weight += a * r;
  }
  out.fourfold = weight > 0 ? std::abs(sum) / weight : 0.0;
  return out;
}

}  // namespace

std::array<Vec3, 3> turn_rows(int axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  std::array<Vec3, 3> r{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  const int u = (axis + 1) % 3, w = (axis + 2) % 3;
  r[u][u] = c, r[u][w] = -s, r[w][u] = s, r[w][w] = c;
  return r;
}

SurfaceMesh turned(const SurfaceMesh& mesh, const std::array<Vec3, 3>& rows, const Vec3& pivot) {
  SurfaceMesh out = mesh;
  for (Vec3& x : out.vertices) x = turn_point(rows, pivot, x);
  return out;
}

}  // namespace chladni::precompute::wave

namespace chladni::precompute {

WaveLayout wave_layout(const SurfaceMesh& mesh, const WaveOptions& options) {
  if (mesh.vertices.empty()) throw InputError("transfer: the surface has no vertices");
  WaveLayout out;
  Vec3 lo = mesh.vertices[0], hi = lo;
  for (const Vec3& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
  out.pivot = scale(add(lo, hi), 0.5);
  const wave::Moments m = wave::moments(mesh);
  out.axis = m.axis, out.fourfold = m.fourfold;
  const bool revolution =
      m.fourfold <= wave::kNearRevolution && m.roundness <= wave::kNearRevolution;
  const int n = revolution ? std::max(1, options.grid_turns) : 1;
  for (int a = 0; a < 3; ++a) out.lo[a] = lo[a], out.hi[a] = hi[a];
  for (int t = 0; t < n; ++t) {
    out.turns.push_back(wave::turn_rows(m.axis, 0.5 * std::numbers::pi * t / n));
    if (t == 0) continue;
    for (const Vec3& x : mesh.vertices) {
      const Vec3 v = wave::turn_point(out.turns.back(), out.pivot, x);
      for (int a = 0; a < 3; ++a)
        out.lo[a] = std::min(out.lo[a], v[a]), out.hi[a] = std::max(out.hi[a], v[a]);
    }
  }
  return out;
}

}  // namespace chladni::precompute
