#version 450
#extension GL_GOOGLE_include_directive : require
// Velocity half step of the staggered grid: w' = a w - b (p[c + e] - p[c]) on the three faces
// above each cell (w = rho0 c v; the last layer on each axis is the rigid outer wall).
layout(local_size_x = 256) in;
#include "wave_common.glsl"

layout(std430, binding = 0) readonly buffer P { float p[]; };
layout(std430, binding = 1) buffer W { float w[]; };  // x faces, y faces, z faces
layout(std430, binding = 2) readonly buffer Coef { float coef[]; };

void main() {
  const uint c = invocation();
  if (c >= pc.n.w) return;
  const uint i = c % pc.n.x, j = (c / pc.n.x) % pc.n.y, k = c / (pc.n.x * pc.n.y);
  const float pc0 = p[c];
  if (i + 1u < pc.n.x) {
    const uint b = coef_base(0u) + 2u * pc.n.x;
    w[c] = coef[b + i] * w[c] - coef[b + pc.n.x + i] * (p[c + 1u] - pc0);
  }
  if (j + 1u < pc.n.y) {
    const uint b = coef_base(1u) + 2u * pc.n.y;
    w[pc.n.w + c] = coef[b + j] * w[pc.n.w + c] - coef[b + pc.n.y + j] * (p[c + pc.n.x] - pc0);
  }
  if (k + 1u < pc.n.z) {
    const uint b = coef_base(2u) + 2u * pc.n.z, s = pc.n.x * pc.n.y;
    w[2u * pc.n.w + c] =
        coef[b + k] * w[2u * pc.n.w + c] - coef[b + pc.n.z + k] * (p[c + s] - pc0);
  }
}
