#version 450
#extension GL_GOOGLE_include_directive : require
// Pressure step: p -= lambda div w inside; in the perfectly matched layer Berenger's split parts
// x' = a x - b dx (and y, z; the z part is p - x - y) are damped per axis.
layout(local_size_x = 256) in;
#include "wave_common.glsl"

layout(std430, binding = 0) buffer P { float p[]; };
layout(std430, binding = 1) buffer Split { float split[]; };  // x parts, then y parts
layout(std430, binding = 2) readonly buffer W { float w[]; };
layout(std430, binding = 3) readonly buffer Coef { float coef[]; };

void main() {
  const uint c = invocation();
  if (c >= pc.n.w) return;
  const uint N = pc.n.w, i = c % pc.n.x, j = (c / pc.n.x) % pc.n.y, k = c / (pc.n.x * pc.n.y);
  const uint s = pc.n.x * pc.n.y;
  const float dx = w[c] - (i > 0u ? w[c - 1u] : 0.0);
  const float dy = w[N + c] - (j > 0u ? w[N + c - pc.n.x] : 0.0);
  const float dz = w[2u * N + c] - (k > 0u ? w[2u * N + c - s] : 0.0);
  const uvec3 q = uvec3(i, j, k);
  if (all(greaterThanEqual(q, pc.pml_lo.xyz)) && all(lessThan(q, pc.pml_hi.xyz))) {
    p[c] -= pc.lambda * (dx + dy + dz);
    return;
  }
  const uint bx = coef_base(0u), by = coef_base(1u), bz = coef_base(2u);
  const float sx = split[c], sy = split[N + c];
  const float x = coef[bx + i] * sx - coef[bx + pc.n.x + i] * dx;
  const float y = coef[by + j] * sy - coef[by + pc.n.y + j] * dy;
  const float z = coef[bz + k] * (p[c] - sx - sy) - coef[bz + pc.n.z + k] * dz;
  split[c] = x;
  split[N + c] = y;
  p[c] = x + y + z;
}
