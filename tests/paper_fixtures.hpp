#pragma once
// Small hand-made paper animations for the paper tests.
#include <cmath>
#include <cstdint>

#include "chladni/core/paper_animation.hpp"

namespace chladni::test {

// An animation over an nx x ny vertex grid (two triangles per cell) and no frames yet.
inline PaperAnimation grid_sheet(std::uint32_t nx, std::uint32_t ny) {
  PaperAnimation a;
  a.vertex_count = nx * ny;
  for (std::uint32_t j = 0; j + 1 < ny; ++j)
    for (std::uint32_t i = 0; i + 1 < nx; ++i) {
      const std::uint32_t p = j * nx + i;
      a.triangles.push_back({p, p + 1, p + nx + 1});
      a.triangles.push_back({p, p + nx + 1, p + nx});
    }
  return a;
}

// A two-frame animation from one flat W x L grid and a map material (u, v) -> position.
template <class F0, class F1>
inline PaperAnimation two_frames(std::uint32_t nx, std::uint32_t ny, double W, double L, F0 frame0,
                                 F1 frame1) {
  PaperAnimation a = grid_sheet(nx, ny);
  for (int f = 0; f < 2; ++f)
    for (std::uint32_t j = 0; j < ny; ++j)
      for (std::uint32_t i = 0; i < nx; ++i) {
        const double u = W * i / (nx - 1), v = L * j / (ny - 1);
        const Vec3 x = f == 0 ? frame0(u, v) : frame1(u, v);
        for (double c : x) a.positions.push_back(float(c));
      }
  return a;
}

inline Vec3 cylinder(double u, double v, double r) {  // axis along x, radius r, arc length v
  return {u, r * std::sin(v / r), r * (1 - std::cos(v / r))};
}

}  // namespace chladni::test
