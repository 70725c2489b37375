#include "surface_sample.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <unordered_map>

#include "chladni/core/error.hpp"

namespace chladni::precompute {
namespace {

struct Closest {
  double distance2 = INFINITY;
  std::array<double, 3> bary{};
  std::size_t triangle = 0;
};

// Barycentric coordinates of the point of triangle abc nearest to p (Ericson, Real-Time
// Collision Detection, 5.1.5).
std::array<double, 3> nearest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b,
                                          const Vec3& c) {
  const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = 1 / (va + vb + vc), v = vb * denom, w = vc * denom;
  return {1 - v - w, v, w};
}

struct VecHash {
  std::size_t operator()(const Vec3& v) const {
    std::size_t h = 0;
    for (double x : v) {
      uint64_t bits;
      std::memcpy(&bits, &x, sizeof bits);
      h = h * 1000003u ^ std::hash<uint64_t>()(bits);
    }
    return h;
  }
};

// Boundary triangles bucketed in a uniform grid for nearest-triangle queries.
class TriangleGrid {
 public:
  TriangleGrid(const std::vector<Vec3>& nodes, const std::vector<std::array<uint32_t, 3>>& tris)
      : nodes_(nodes), tris_(tris) {
    lo_ = {INFINITY, INFINITY, INFINITY};
    Vec3 hi{-INFINITY, -INFINITY, -INFINITY};
    double edges = 0;
    for (const auto& t : tris) {
      for (uint32_t v : t)
        for (int k = 0; k < 3; ++k)
          lo_[k] = std::min(lo_[k], nodes[v][k]), hi[k] = std::max(hi[k], nodes[v][k]);
      const Vec3 d = sub(nodes[t[1]], nodes[t[0]]);
      edges += std::sqrt(dot(d, d));
    }
    cell_ = std::max(2 * edges / double(std::max<std::size_t>(tris.size(), 1)), 1e-12);
    for (int k = 0; k < 3; ++k) n_[k] = std::clamp(int((hi[k] - lo_[k]) / cell_) + 1, 1, 256);
    cells_.resize(std::size_t(n_[0]) * n_[1] * n_[2]);
    for (std::size_t i = 0; i < tris.size(); ++i) {
      std::array<int, 3> a{}, b{};
      for (int k = 0; k < 3; ++k) {
        double mn = INFINITY, mx = -INFINITY;
        for (uint32_t v : tris[i]) mn = std::min(mn, nodes[v][k]), mx = std::max(mx, nodes[v][k]);
        a[k] = index(mn, k), b[k] = index(mx, k);
      }
      for (int x = a[0]; x <= b[0]; ++x)
        for (int y = a[1]; y <= b[1]; ++y)
          for (int z = a[2]; z <= b[2]; ++z) cells_[flat(x, y, z)].push_back(uint32_t(i));
    }
  }

  Closest nearest(const Vec3& p) const {
    Closest best;
    const std::array<int, 3> c{index(p[0], 0), index(p[1], 1), index(p[2], 2)};
    for (int r = 1; r <= std::max({n_[0], n_[1], n_[2]}); r *= 2) {
      for (int x = std::max(0, c[0] - r); x <= std::min(n_[0] - 1, c[0] + r); ++x)
        for (int y = std::max(0, c[1] - r); y <= std::min(n_[1] - 1, c[1] + r); ++y)
          for (int z = std::max(0, c[2] - r); z <= std::min(n_[2] - 1, c[2] + r); ++z)
            for (uint32_t i : cells_[flat(x, y, z)]) consider(p, i, best);
      // Anything nearer than r cells lies in the block searched.
      if (best.distance2 <= (r * cell_) * (r * cell_)) break;
    }
    return best;
  }

 private:
  int index(double x, int k) const { return std::clamp(int((x - lo_[k]) / cell_), 0, n_[k] - 1); }
  std::size_t flat(int x, int y, int z) const {
    return (std::size_t(x) * n_[1] + std::size_t(y)) * n_[2] + std::size_t(z);
  }
  void consider(const Vec3& p, uint32_t i, Closest& best) const {
    const auto& t = tris_[i];
    const auto b = nearest_on_triangle(p, nodes_[t[0]], nodes_[t[1]], nodes_[t[2]]);
    Vec3 q{0, 0, 0};
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) q[k] += b[j] * nodes_[t[j]][k];
    const Vec3 d = sub(q, p);
    if (dot(d, d) < best.distance2) best = {dot(d, d), b, i};
  }

  const std::vector<Vec3>& nodes_;
  const std::vector<std::array<uint32_t, 3>>& tris_;
  Vec3 lo_;
  double cell_ = 1;
  std::array<int, 3> n_{};
  std::vector<std::vector<uint32_t>> cells_;
};

}  // namespace

Eigen::MatrixXd sample_on_surface(const TetMesh& tets, const Eigen::MatrixXd& vectors,
                                  const SurfaceMesh& surface) {
  if (vectors.rows() < Eigen::Index(3 * tets.nodes.size()))
    throw InternalError("sample_on_surface: the vectors do not belong to this mesh");
  std::unordered_map<Vec3, uint32_t, VecHash> at;
  for (std::size_t v = 0; v < tets.surface_vertices; ++v) at.emplace(tets.nodes[v], uint32_t(v));
  Eigen::MatrixXd out(Eigen::Index(3 * surface.vertices.size()), vectors.cols());
  std::unique_ptr<TriangleGrid> grid;  // built on the first vertex that needs it
  for (std::size_t v = 0; v < surface.vertices.size(); ++v) {
    const auto row = Eigen::Index(3 * v);
    if (auto it = at.find(surface.vertices[v]); it != at.end()) {
      out.middleRows(row, 3) = vectors.middleRows(Eigen::Index(3 * it->second), 3);
      continue;
    }
    if (!grid) grid = std::make_unique<TriangleGrid>(tets.nodes, tets.surface_triangles);
    const Closest c = grid->nearest(surface.vertices[v]);
    out.middleRows(row, 3).setZero();
    for (int j = 0; j < 3; ++j)
      out.middleRows(row, 3) +=
          c.bary[j] *
          vectors.middleRows(Eigen::Index(3 * tets.surface_triangles[c.triangle][j]), 3);
  }
  return out;
}

}  // namespace chladni::precompute
