#include "chladni/runtime/modal/gain_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "filterbank/cpu_kernels.hpp"

#if CHLADNI_X86_64
#include <immintrin.h>
#endif

// Evaluation side of the far-field maps: directions, cells and the per-update loop.
namespace chladni::runtime {

GridCell grid_cell(uint32_t rows, uint32_t cols, const MapDirection& d) {
  const double tt = d.theta * double(rows - 1);
  const uint32_t j0 = std::min(static_cast<uint32_t>(tt), rows - 2);
  const double ft = std::clamp(tt - j0, 0.0, 1.0);
  const double tp = d.phi * double(cols);
  const uint32_t c0 = std::min(static_cast<uint32_t>(tp), cols - 1);
  const double fp = std::clamp(tp - c0, 0.0, 1.0);
  const uint32_t c1 = (c0 + 1) % cols;
  GridCell c;
  c.node[0] = j0 * cols + c0;
  c.node[1] = j0 * cols + c1;
  c.node[2] = (j0 + 1) * cols + c0;
  c.node[3] = (j0 + 1) * cols + c1;
  c.weight[0] = float((1 - ft) * (1 - fp));
  c.weight[1] = float((1 - ft) * fp);
  c.weight[2] = float(ft * (1 - fp));
  c.weight[3] = float(ft * fp);
  return c;
}

MapDirection map_direction(const Vec3& d) {
  const double r = std::sqrt(dot(d, d));
  const double z = r > 0 ? std::clamp(d[2] / r, -1.0, 1.0) : 1.0;
  double phi = std::atan2(d[1], d[0]);
  if (phi < 0) phi += 2 * std::numbers::pi;
  return {std::acos(z) / std::numbers::pi, std::min(phi / (2 * std::numbers::pi), 1.0)};
}

GridCell GainMap::Grid::cell(const MapDirection& d) const {
  return grid_cell(rows, cols, d);
}

int GainMap::series_order(float r) const {
  const auto it = std::upper_bound(step_radius.begin(), step_radius.end(), r);
  return it == step_radius.end() ? -1 : step_order[it - step_radius.begin()];
}

std::size_t GainMap::bytes() const {
  std::size_t b = 0;
  for (const Grid& g : grids) b += g.coef.size() * sizeof(uint16_t);
  return b;
}

namespace {

float half_to_float(uint16_t h) {
  _Float16 f;
  std::memcpy(&f, &h, sizeof f);
  return static_cast<float>(f);
}

struct GridLoop {
  const uint16_t* p[4];
  float w[4];
  const float *scale, *valid;
  std::size_t cnt;
  float s;
};

float slot_gain(const GridLoop& g, float c[6], std::size_t j) {
  const float u = g.s * g.valid[j];  // s r_v: the normalized coefficients' variable
  const float re = c[0] + u * (c[2] + u * c[4]), im = c[1] + u * (c[3] + u * c[5]);
  return std::sqrt(re * re + im * im) * g.scale[j] * g.s;
}

void gains_scalar(const GridLoop& g, std::size_t b, std::size_t e, float* block) {
  for (std::size_t j = b; j < e; ++j) {
    float c[6];
    for (std::size_t q = 0; q < 6; ++q) {
      const std::size_t o = q * g.cnt + j;
      c[q] = 0;
      for (int n = 0; n < 4; ++n) c[q] += g.w[n] * half_to_float(g.p[n][o]);
    }
    block[j - b] = slot_gain(g, c, j);
  }
}

#if CHLADNI_X86_64
// Eight slots at a time with F16C conversions (GCC 12 does not vectorize _Float16 loads).
[[gnu::target("avx2,f16c,fma")]] void gains8(const GridLoop& g, const uint16_t* const* p,
                                             std::size_t stride, const float* valid,
                                             const float* scale, float* out) {
  const __m256 us = _mm256_set1_ps(g.s);
  __m256 c[6];
  for (std::size_t q = 0; q < 6; ++q) {
    __m256 acc = _mm256_setzero_ps();
    for (int n = 0; n < 4; ++n) {
      const auto* src = reinterpret_cast<const __m128i*>(p[n] + q * stride);
      acc = _mm256_fmadd_ps(_mm256_set1_ps(g.w[n]), _mm256_cvtph_ps(_mm_loadu_si128(src)), acc);
    }
    c[q] = acc;
  }
  const __m256 u = _mm256_mul_ps(us, _mm256_loadu_ps(valid));
  const __m256 re = _mm256_fmadd_ps(u, _mm256_fmadd_ps(u, c[4], c[2]), c[0]);
  const __m256 im = _mm256_fmadd_ps(u, _mm256_fmadd_ps(u, c[5], c[3]), c[1]);
  const __m256 mag = _mm256_sqrt_ps(_mm256_fmadd_ps(re, re, _mm256_mul_ps(im, im)));
  _mm256_storeu_ps(out, _mm256_mul_ps(_mm256_mul_ps(mag, _mm256_loadu_ps(scale)), us));
}

// Eight slots at a time with F16C conversions (GCC 12 does not vectorize _Float16 loads).
[[gnu::target("avx2,f16c,fma")]] void gains_avx2(const GridLoop& g, std::size_t b, std::size_t e,
                                                 float* block) {
  std::size_t j = b;
  for (; j + 8 <= e; j += 8) {
    const uint16_t* p[4] = {g.p[0] + j, g.p[1] + j, g.p[2] + j, g.p[3] + j};
    gains8(g, p, g.cnt, g.valid + j, g.scale + j, block + (j - b));
  }
  for (; j < e; ++j) {  // the last few: scalar F16C conversions
    float c[6];
    for (std::size_t q = 0; q < 6; ++q) {
      const std::size_t o = q * g.cnt + j;
      c[q] = 0;
      for (int n = 0; n < 4; ++n) c[q] += g.w[n] * _cvtsh_ss(g.p[n][o]);
    }
    block[j - b] = slot_gain(g, c, j);
  }
}

// The filterbank's AVX2 + FMA check, plus the half-precision conversions.
bool has_avx2_f16c() {
  static const bool yes = cpu::isa_supported(cpu::Isa::Avx2) && __builtin_cpu_supports("f16c");
  return yes;
}
#endif

}  // namespace

void grid_gains(const GainMap::Grid& g, const GridCell& cell, float s, float* out) {
  GridLoop loop;
  loop.cnt = g.stride;
  for (int n = 0; n < 4; ++n) {
    loop.p[n] = g.coef.data() + std::size_t(cell.node[n]) * 6 * loop.cnt;
    loop.w[n] = cell.weight[n];
  }
  loop.scale = g.scale.data();
  loop.valid = g.valid.data();
  loop.s = s;
  constexpr std::size_t kBlock = 64;  // computed contiguously, then scattered to the modes
  float block[kBlock];
  for (std::size_t b = 0; b < loop.cnt; b += kBlock) {
    const std::size_t e = std::min(loop.cnt, b + kBlock);
#if CHLADNI_X86_64
    if (has_avx2_f16c())
      gains_avx2(loop, b, e, block);
    else
#endif
      gains_scalar(loop, b, e, block);
    for (std::size_t j = b; j < e; ++j) out[g.modes[j]] = block[j - b];
  }
}

}  // namespace chladni::runtime
