#include "surface_pieces.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <numeric>
#include <unordered_map>
#include <utility>

#include "../edge_key.hpp"
#include "../union_find.hpp"
#include "chladni/core/error.hpp"

namespace chladni::precompute {
namespace {

// Nesting compares one point of each piece with every triangle: skipped above this many pairs
// (a soup of thousands of fragments), where the pieces are then reported as separate.
constexpr double kMaxNestingPairs = 5e7;

void nest(const SurfaceMesh& m, SurfacePieces& s) {
  const std::size_t n = s.count();
  // winding[i * n + j]: piece j's winding number about a point of piece i (+-1 inside, 0 out).
  std::vector<double> winding(n * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& t = m.triangles[s.first_triangle[i]];
    const Vec3 p = scale(add(add(m.vertices[t[0]], m.vertices[t[1]]), m.vertices[t[2]]), 1.0 / 3);
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
      const std::size_t j = s.of_triangle[f];
      if (j == i) continue;
      const auto& u = m.triangles[f];
      winding[i * n + j] += solid_angle(p, m.vertices[u[0]], m.vertices[u[1]], m.vertices[u[2]]);
    }
  }
  s.depth.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      s.depth[i] += j != i && std::abs(winding[i * n + j]) > 2 * std::numbers::pi;
  s.parent.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      if (j != i && std::abs(winding[i * n + j]) > 2 * std::numbers::pi &&
          (s.parent[i] < 0 || s.depth[j] > s.depth[std::size_t(s.parent[i])]))
        s.parent[i] = int(j);
}

}  // namespace

double solid_angle(const Vec3& p, const Vec3& a0, const Vec3& b0, const Vec3& c0) {
  const Vec3 a = sub(a0, p), b = sub(b0, p), c = sub(c0, p);
  const double la = norm(a), lb = norm(b), lc = norm(c);
  const double num = dot(a, cross(b, c));
  const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return 2 * std::atan2(num, den);
}

SurfacePieces surface_pieces(const SurfaceMesh& m) {
  const std::size_t nt = m.triangles.size();
  UnionFind pieces(nt);
  std::unordered_map<std::uint64_t, std::size_t> first;
  first.reserve(3 * nt / 2);
  for (std::size_t f = 0; f < nt; ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = m.triangles[f][k], b = m.triangles[f][(k + 1) % 3];
      if (a == b) continue;
      auto [it, fresh] = first.emplace(edge_key(a, b), f);
      if (!fresh) pieces.unite(f, it->second);
    }
  SurfacePieces s;
  s.of_triangle.resize(nt);
  std::unordered_map<std::size_t, uint32_t> index;
  for (std::size_t f = 0; f < nt; ++f) {
    auto [it, fresh] = index.emplace(pieces.find(f), uint32_t(s.volume.size()));
    if (fresh) {
      s.first_triangle.push_back(f);
      s.triangles.push_back(0);
      s.volume.push_back(0);
    }
    const uint32_t p = s.of_triangle[f] = it->second;
    const auto& t = m.triangles[f];
    s.triangles[p]++;
    // Divergence theorem: signed tetrahedra to the origin.
    s.volume[p] += dot(m.vertices[t[0]], cross(m.vertices[t[1]], m.vertices[t[2]])) / 6;
  }
  if (s.count() > 1 && double(s.count()) * double(nt) <= kMaxNestingPairs) nest(m, s);
  return s;
}

double ray_depth(const SurfaceMesh& m, const Vec3& o, const Vec3& dir, uint32_t skip, double eps) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    if (t[0] == skip || t[1] == skip || t[2] == skip) continue;
    const Vec3& a = m.vertices[t[0]];
    const Vec3 e1 = sub(m.vertices[t[1]], a), e2 = sub(m.vertices[t[2]], a);
    const Vec3 p = cross(dir, e2);
    const double det = dot(e1, p);
    if (std::abs(det) < 1e-300) continue;
    const double inv = 1.0 / det;
    const Vec3 s = sub(o, a);
    const double u = dot(s, p) * inv;
    if (u < 0.0 || u > 1.0) continue;
    const Vec3 q = cross(s, e1);
    const double v = dot(dir, q) * inv;
    if (v < 0.0 || u + v > 1.0) continue;
    const double tt = dot(e2, q) * inv;
    if (tt > eps && tt < best) best = tt;
  }
  return best;
}

Vec3 point_in_cavity(const SurfaceMesh& m, const SurfacePieces& s, std::size_t piece) {
  std::vector<std::pair<double, std::size_t>> faces;  // (twice the area, face), largest first
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    const auto& t = m.triangles[f];
    if (s.of_triangle[f] == piece)
      faces.emplace_back(
          norm(triangle_normal(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]])), f);
  }
  std::sort(faces.begin(), faces.end(), std::greater<>());
  const SurfaceMesh piece_only = keep_pieces(m, s, [&] {
    std::vector<bool> k(s.count(), false);
    k[piece] = true;
    return k;
  }());
  // A ray may graze an edge of the far side and miss; a few faces make that irrelevant.
  for (std::size_t k = 0; k < std::min<std::size_t>(faces.size(), 8); ++k) {
    const auto& t = m.triangles[faces[k].second];
    const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    const Vec3 n2 = triangle_normal(a, b, c);
    const double len = norm(n2);
    if (!(len > 0)) continue;
    const Vec3 dir = scale(n2, 1 / len), from = scale(add(add(a, b), c), 1.0 / 3);
    const double size = std::sqrt(len);
    const double d = ray_depth(piece_only, from, dir, UINT32_MAX, 1e-9 * size);
    if (std::isfinite(d)) return add(from, scale(dir, 0.5 * d));
  }
  throw InternalError("found no point inside a cavity of the surface");
}

SurfaceMesh keep_pieces(const SurfaceMesh& m, const SurfacePieces& s,
                        const std::vector<bool>& keep) {
  constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> to(m.vertices.size(), kNone);
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    if (keep[s.of_triangle[f]])
      for (uint32_t v : m.triangles[f]) to[v] = 0;
  SurfaceMesh out;
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    if (to[v] != kNone) {
      to[v] = uint32_t(out.vertices.size());
      out.vertices.push_back(m.vertices[v]);
    }
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    if (keep[s.of_triangle[f]]) {
      const auto& t = m.triangles[f];
      out.triangles.push_back({to[t[0]], to[t[1]], to[t[2]]});
    }
  return out;
}

SurfaceMesh outer_surface(const SurfaceMesh& m) {
  const SurfacePieces s = surface_pieces(m);
  if (!s.nested()) return m;
  std::vector<bool> keep(s.count());
  for (std::size_t p = 0; p < s.count(); ++p) keep[p] = s.depth[p] == 0;
  return keep_pieces(m, s, keep);
}

}  // namespace chladni::precompute
