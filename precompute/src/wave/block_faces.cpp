// Rasterizing the surface onto the staggered grid: lines along each axis through the cell
// centres, intersected with every triangle that covers them.
#include <algorithm>
#include <cmath>

#include "wave_grid.hpp"

namespace chladni::precompute::wave {
namespace {

constexpr double kEdge = 1e-9;  // barycentric and along-line tolerance (cell units)

struct Hit {
  uint64_t line;  // j + n_b k
  double s;       // position along the axis in cell units (centre i at s = i)
  uint32_t tri;
  std::array<float, 3> bary;
};

// All crossings of lines along `axis` with the triangles, sorted along each line.
std::vector<Hit> crossings(const SurfaceMesh& mesh, const Grid& g, int a) {
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  std::vector<Hit> hits;
  auto unit = [&](const Vec3& v, int axis) { return (v[axis] - g.origin[axis]) / g.h - 0.5; };
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    double u[3], v[3], s[3];
    for (int q = 0; q < 3; ++q) {
      const Vec3& p = mesh.vertices[tri[q]];
      u[q] = unit(p, b), v[q] = unit(p, c), s[q] = unit(p, a);
    }
    const double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    if (area == 0) continue;  // seen edge-on from this axis: the other axes see it
    const long j0 = std::max(0L, long(std::ceil(std::min({u[0], u[1], u[2]}))));
    const long j1 = std::min(long(g.n[b]) - 1, long(std::floor(std::max({u[0], u[1], u[2]}))));
    const long k0 = std::max(0L, long(std::ceil(std::min({v[0], v[1], v[2]}))));
    const long k1 = std::min(long(g.n[c]) - 1, long(std::floor(std::max({v[0], v[1], v[2]}))));
    for (long k = k0; k <= k1; ++k) {
      for (long j = j0; j <= j1; ++j) {
        // Barycentric coordinates of the line's foot in the projected triangle.
        const double x = double(j), y = double(k);
        const double l1 = ((x - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (y - v[0])) / area;
        const double l2 = ((u[1] - u[0]) * (y - v[0]) - (x - u[0]) * (v[1] - v[0])) / area;
        const double l0 = 1.0 - l1 - l2;
        // Inclusive by a hair: a line through an edge or a vertex is caught by every triangle
        // there, never by none (the duplicates are dropped below).
        if (l0 < -kEdge || l1 < -kEdge || l2 < -kEdge) continue;
        hits.push_back({uint64_t(j) + uint64_t(g.n[b]) * uint64_t(k),
                        l0 * s[0] + l1 * s[1] + l2 * s[2],
                        t,
                        {float(l0), float(l1), float(l2)}});
      }
    }
  }
  std::sort(hits.begin(), hits.end(), [](const Hit& x, const Hit& y) {
    return x.line != y.line ? x.line < y.line : x.s < y.s;
  });
  std::vector<Hit> unique;
  for (const Hit& h : hits)
    if (unique.empty() || unique.back().line != h.line || h.s - unique.back().s > kEdge)
      unique.push_back(h);
  return unique;
}

Vec3 unit_normal(const SurfaceMesh& mesh, uint32_t t) {
  const auto& tri = mesh.triangles[t];
  const Vec3 n =
      triangle_normal(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]);
  const double l = norm(n);
  return l > 0 ? scale(n, 1.0 / l) : Vec3{0, 0, 0};
}

}  // namespace

BlockedFaces block_faces(const SurfaceMesh& mesh, const Grid& g) {
  BlockedFaces out;
  out.start.push_back(0);
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const std::vector<Hit> hits = crossings(mesh, g, a);
    const long na = long(g.n[a]);
    for (std::size_t h0 = 0; h0 < hits.size();) {
      std::size_t h1 = h0;
      while (h1 < hits.size() && hits[h1].line == hits[h0].line) ++h1;
      const uint64_t line = hits[h0].line;
      const uint64_t j = line % g.n[b], k = line / g.n[b];
      auto cell_at = [&](long i) {
        std::array<uint64_t, 3> idx{};
        idx[a] = uint64_t(i), idx[b] = j, idx[c] = k;
        return idx[0] + uint64_t(g.n[0]) * (idx[1] + uint64_t(g.n[1]) * idx[2]);
      };
      // Faces: hits between centres i and i + 1 block face i.
      for (std::size_t q = h0; q < h1;) {
        const long i = long(std::floor(hits[q].s));
        std::size_t r = q;
        while (r < h1 && long(std::floor(hits[r].s)) == i) ++r;
        if (i >= 0 && i + 1 < na) {
          out.axis.push_back(uint32_t(a));
          out.cell.push_back(cell_at(i));
          const float share = 1.0f / float(r - q);
          for (std::size_t e = q; e < r; ++e) {
            const auto& tri = mesh.triangles[hits[e].tri];
            const Vec3 n = unit_normal(mesh, hits[e].tri);
            const std::array<float, 3> d{float(n[0] * n[a]), float(n[1] * n[a]),
                                         float(n[2] * n[a])};
            const float reach = float((double(i) + 0.5 - hits[e].s) * g.h * n[a]);
            for (int v = 0; v < 3; ++v) {
              out.vertex.push_back(tri[v]);
              out.weight.push_back(hits[e].bary[v] * share);
              out.direction.push_back(d);
              out.reach.push_back(reach);
            }
          }
          out.start.push_back(uint32_t(out.vertex.size()));
        }
        q = r;
      }
      h0 = h1;
    }
  }
  return out;
}

RecordFaces record_box(const Grid& g, const std::array<uint32_t, 3>& lo,
                       const std::array<uint32_t, 3>& hi) {
  RecordFaces r;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      // Lower plane: the face between cells lo-1 and lo; upper: between hi-1 and hi.
      const uint64_t ia = side == 0 ? lo[a] - 1 : hi[a] - 1;
      for (uint64_t k = lo[c]; k < hi[c]; ++k) {
        for (uint64_t j = lo[b]; j < hi[b]; ++j) {
          std::array<uint64_t, 3> idx{};
          idx[a] = ia, idx[b] = j, idx[c] = k;
          r.axis.push_back(uint32_t(a));
          r.cell.push_back(idx[0] + uint64_t(g.n[0]) * (idx[1] + uint64_t(g.n[1]) * idx[2]));
          r.sign.push_back(side == 0 ? -1 : 1);
        }
      }
    }
  }
  return r;
}

}  // namespace chladni::precompute::wave
