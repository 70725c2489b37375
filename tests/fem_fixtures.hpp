#pragma once
// Closed surfaces made in code for the FEM tests and the convergence study: a subdivided
// icosahedron on a sphere and a box with a regular grid on each face.
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <vector>

#include "chladni/core/soundbank.hpp"
#include "chladni/core/vec3.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::test {

using precompute::SurfaceMesh;

// Unit icosahedron subdivided `level` times and projected onto the sphere of radius r.
inline SurfaceMesh icosphere(double r, int level) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  SurfaceMesh m;
  m.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto [it, fresh] = mid.emplace(std::minmax(a, b), uint32_t(m.vertices.size()));
      if (fresh) {
        const Vec3 &p = m.vertices[a], &q = m.vertices[b];
        m.vertices.push_back({(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2});
      }
      return it->second;
    };
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& f : m.triangles) {
      const uint32_t a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c}), next.push_back({f[1], b, a}), next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  for (Vec3& v : m.vertices) {
    const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (double& x : v) x *= r / l;
  }
  return m;
}

// A soundbank with icosphere(r, level)'s surface and its exact normals, and no modes yet: the
// radiation tests add modes that move it.
inline Soundbank sphere_surface_bank(double r, int level) {
  const SurfaceMesh s = icosphere(r, level);
  Soundbank bank;
  bank.vertices = s.vertices;
  bank.triangles = s.triangles;
  for (const Vec3& v : s.vertices) {
    const Vec3 n = scale(v, 1.0 / norm(v));
    bank.normals.push_back({float(n[0]), float(n[1]), float(n[2])});
  }
  return bank;
}

/// Box [0, L] x [0, W] x [0, H] with n[0] x n[1] x n[2] cells on its faces, outward triangles.
inline SurfaceMesh box_surface(const Vec3& size, const std::array<int, 3>& n) {
  SurfaceMesh m;
  std::map<std::array<int, 3>, uint32_t> index;
  auto vertex = [&](int i, int j, int k) {
    auto [it, fresh] = index.emplace(std::array<int, 3>{i, j, k}, uint32_t(m.vertices.size()));
    if (fresh) m.vertices.push_back({size[0] * i / n[0], size[1] * j / n[1], size[2] * k / n[2]});
    return it->second;
  };
  // For each axis a and side s, a grid over the other two axes (b, c) with (b, c, a) right-handed.
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int side = 0; side < 2; ++side)
      for (int u = 0; u < n[b]; ++u)
        for (int v = 0; v < n[c]; ++v) {
          uint32_t q[4];
          const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> p;
            p[a] = side * n[a], p[b] = u + du[k], p[c] = v + dv[k];
            q[k] = vertex(p[0], p[1], p[2]);
          }
          if (side == 1) {
            m.triangles.push_back({q[0], q[1], q[2]}), m.triangles.push_back({q[0], q[2], q[3]});
          } else {
            m.triangles.push_back({q[0], q[2], q[1]}), m.triangles.push_back({q[0], q[3], q[2]});
          }
        }
  }
  return m;
}

/// An L-section prism: a `block` x `block` square section with a fin of thickness `fin` reaching
/// to x = `reach`, extruded `depth` along y; outward triangles. The thin fin holds the error of
/// a uniform mesh.
inline SurfaceMesh l_section_surface(double block, double fin, double reach, double depth) {
  const double P[7][2] = {{0, 0},       {block, 0},     {reach, 0}, {reach, fin},
                          {block, fin}, {block, block}, {0, block}};  // (x, z), counter-clockwise
  SurfaceMesh m;
  for (double y : {0.0, depth})
    for (const auto& p : P) m.vertices.push_back({p[0], y, p[1]});
  auto add = [&](uint32_t a, uint32_t b, uint32_t c, const Vec3& out) {
    const Vec3 n = cross(sub(m.vertices[b], m.vertices[a]), sub(m.vertices[c], m.vertices[a]));
    if (dot(n, out) > 0)
      m.triangles.push_back({a, b, c});
    else
      m.triangles.push_back({a, c, b});
  };
  const uint32_t caps[5][3] = {{0, 1, 4}, {0, 4, 5}, {0, 5, 6}, {1, 2, 3}, {1, 3, 4}};
  for (const auto& t : caps) {
    add(t[0], t[1], t[2], {0, -1, 0});
    add(t[0] + 7, t[1] + 7, t[2] + 7, {0, 1, 0});
  }
  for (uint32_t i = 0; i < 7; ++i) {
    const uint32_t j = (i + 1) % 7;
    const Vec3 out{P[j][1] - P[i][1], 0, P[i][0] - P[j][0]};
    add(i, j, j + 7, out);
    add(i, j + 7, i + 7, out);
  }
  return m;
}

/// `inner` appended to `outer`, its winding reversed when `reverse` (a cavity's faces point into
/// it).
inline SurfaceMesh with_piece(SurfaceMesh outer, const SurfaceMesh& inner, bool reverse) {
  const uint32_t base = uint32_t(outer.vertices.size());
  outer.vertices.insert(outer.vertices.end(), inner.vertices.begin(), inner.vertices.end());
  for (auto t : inner.triangles) {
    for (uint32_t& v : t) v += base;
    if (reverse) std::swap(t[1], t[2]);
    outer.triangles.push_back(t);
  }
  return outer;
}

/// The volume a closed, outward-wound surface encloses (divergence theorem).
inline double enclosed_volume(const SurfaceMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles)
    v += dot(m.vertices[t[0]], cross(m.vertices[t[1]], m.vertices[t[2]])) / 6;
  return v;
}

/// A hollow ball: icospheres of radius r and r - wall, the inner one wound into the cavity.
inline SurfaceMesh hollow_sphere(double r, double wall, int level) {
  return with_piece(icosphere(r, level), icosphere(r - wall, level), true);
}

/// A disc of radius r and thickness h as an n-gon prism whose caps are fans from their centres
/// (as CAD programs export one), outward triangles.
inline SurfaceMesh disc_prism(double r, double h, int n) {
  SurfaceMesh m;
  m.vertices = {{0, 0, 0}, {0, 0, h}};
  for (double z : {0.0, h})
    for (int i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n;
      m.vertices.push_back({r * std::cos(a), r * std::sin(a), z});
    }
  const uint32_t rim = 2, top = 2 + uint32_t(n);
  for (uint32_t i = 0; i < uint32_t(n); ++i) {
    const uint32_t j = (i + 1) % uint32_t(n);
    m.triangles.push_back({0, rim + j, rim + i});
    m.triangles.push_back({1, top + i, top + j});
    m.triangles.push_back({rim + i, rim + j, top + j});
    m.triangles.push_back({rim + i, top + j, top + i});
  }
  return m;
}

enum class BarMode { BendZ, BendY, Other };

// Bar modes by shape: mostly across z (thickness) or y (width), and bending (the transverse
// motion is mirror-symmetric across the section) rather than torsion (antisymmetric).
inline std::vector<BarMode> classify_bar_modes(const Soundbank& b) {
  const std::size_t nv = b.vertices.size();
  Vec3 c{0, 0, 0};
  for (const Vec3& v : b.vertices)
    for (int k = 0; k < 3; ++k) c[k] += v[k] / double(nv);
  // mirror[axis][v]: the vertex nearest to v reflected across the centre plane normal to axis.
  std::vector<std::size_t> mirror[3];
  for (int axis : {1, 2}) {
    for (std::size_t v = 0; v < nv; ++v) {
      Vec3 p = b.vertices[v];
      p[axis] = 2 * c[axis] - p[axis];
      std::size_t best = 0;
      double best_d = INFINITY;
      for (std::size_t w = 0; w < nv; ++w) {
        const double dx = b.vertices[w][0] - p[0], dy = b.vertices[w][1] - p[1],
                     dz = b.vertices[w][2] - p[2];
        const double d = dx * dx + dy * dy + dz * dz;
        if (d < best_d) best_d = d, best = w;
      }
      mirror[axis].push_back(best);
    }
  }
  std::vector<BarMode> out;
  for (std::size_t i = 0; i < b.mode_count(); ++i) {
    auto s = [&](std::size_t v, int k) { return double(b.shapes[(i * nv + v) * 3 + k]); };
    double e[3] = {0, 0, 0}, sym_z = 0, sym_y = 0;
    for (std::size_t v = 0; v < nv; ++v) {
      for (int k = 0; k < 3; ++k) e[k] += s(v, k) * s(v, k);
      sym_z += s(v, 2) * s(mirror[1][v], 2);  // z motion mirrored across the width
      sym_y += s(v, 1) * s(mirror[2][v], 1);  // y motion mirrored across the thickness
    }
    const double total = e[0] + e[1] + e[2];
    if (e[2] > 0.6 * total && sym_z > 0.5 * e[2])
      out.push_back(BarMode::BendZ);
    else if (e[1] > 0.6 * total && sym_y > 0.5 * e[1])
      out.push_back(BarMode::BendY);
    else
      out.push_back(BarMode::Other);
  }
  return out;
}

}  // namespace chladni::test
