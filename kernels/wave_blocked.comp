#version 450
#extension GL_GOOGLE_include_directive : require
// Faces crossed by the surface take the surface's velocity along their axis: the chord's modal
// velocities at this step weighted by each mode's shape there. extra.x: faces, extra.y: modes,
// extra.z: step.
layout(local_size_x = 256) in;
#include "wave_common.glsl"

layout(std430, binding = 0) readonly buffer Faces { uint face[]; };  // axis * cells + cell
layout(std430, binding = 1) readonly buffer Amplitude { float amplitude[]; };
layout(std430, binding = 2) readonly buffer Drive { float drive[]; };
layout(std430, binding = 3) buffer W { float w[]; };

void main() {
  const uint f = invocation();
  if (f >= pc.extra.x) return;
  const uint J = pc.extra.y;
  float v = 0.0;
  for (uint m = 0u; m < J; ++m) v += amplitude[f * J + m] * drive[pc.extra.z * J + m];
  w[face[f]] = v;
}
