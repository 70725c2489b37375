#version 450
#extension GL_GOOGLE_include_directive : require
// One sample of the recording box: per face p (four-point interpolation along the face's
// axis, wave_cpu.cpp) and w. extra.x: faces,
// extra.y: sample slot in the buffer.
layout(local_size_x = 256) in;
#include "wave_common.glsl"

layout(std430, binding = 0) readonly buffer Faces { uvec2 face[]; };  // w index, cell stride
layout(std430, binding = 1) readonly buffer P { float p[]; };
layout(std430, binding = 2) readonly buffer W { float w[]; };
layout(std430, binding = 3) writeonly buffer Samples { vec2 samples[]; };

void main() {
  const uint q = invocation();
  if (q >= pc.extra.x) return;
  const uvec2 f = face[q];
  const uint c = f.x % pc.n.w;
  const float pf = (9.0 * (p[c] + p[c + f.y]) - (p[c - f.y] + p[c + 2u * f.y])) * (1.0 / 16.0);
  samples[pc.extra.y * pc.extra.x + q] = vec2(pf, w[f.x]);
}
