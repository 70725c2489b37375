// Boundary elements finer than the surface: each triangle split into four at its edge midpoints,
// level by level, remembering where each element lies in its original triangle.
#include <map>
#include <utility>

#include "chladni/precompute/acoustic_transfer.hpp"

namespace chladni::precompute {

BemSurface::BemSurface(const SurfaceMesh& base, int levels) : level(levels), mesh(base) {
  using Bary = std::array<double, 3>;
  const std::size_t n = base.triangles.size();
  parent.resize(n);
  corners.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    parent[t] = static_cast<uint32_t>(t);
    corners[t] = {Bary{1, 0, 0}, Bary{0, 1, 0}, Bary{0, 0, 1}};
  }
  auto mid = [](const Bary& a, const Bary& b) {
    return Bary{0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
  };
  for (int l = 0; l < levels; ++l) {
    SurfaceMesh next;
    next.vertices = mesh.vertices;
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;  // shared by both triangles
    auto vertex_between = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto [it, fresh] = midpoint.try_emplace({key.first, key.second}, 0u);
      if (fresh) {
        it->second = static_cast<uint32_t>(next.vertices.size());
        next.vertices.push_back(scale(add(mesh.vertices[a], mesh.vertices[b]), 0.5));
      }
      return it->second;
    };
    std::vector<uint32_t> next_parent;
    std::vector<std::array<Bary, 3>> next_corners;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto [a, b, c] = mesh.triangles[t];
      const uint32_t ab = vertex_between(a, b), bc = vertex_between(b, c),
                     ca = vertex_between(c, a);
      const auto& k = corners[t];
      const Bary kab = mid(k[0], k[1]), kbc = mid(k[1], k[2]), kca = mid(k[2], k[0]);
      // Same orientation as the parent: three corner triangles and the middle one.
      const std::array<std::array<uint32_t, 3>, 4> tri = {
          {{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}}};
      const std::array<std::array<Bary, 3>, 4> bary = {
          {{k[0], kab, kca}, {kab, k[1], kbc}, {kca, kbc, k[2]}, {kab, kbc, kca}}};
      for (int s = 0; s < 4; ++s) {
        next.triangles.push_back(tri[s]);
        next_parent.push_back(parent[t]);
        next_corners.push_back(bary[s]);
      }
    }
    mesh = std::move(next);
    parent = std::move(next_parent);
    corners = std::move(next_corners);
  }
}

}  // namespace chladni::precompute
