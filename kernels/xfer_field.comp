#version 450
#extension GL_GOOGLE_include_directive : require
// Pressure of equivalent sources at field points: p(x_j) = sum_s q_s e^(ikr) / (4 pi r),
// r = |x_j - y_s|. One invocation per field point.
#include "complex_math.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Points { vec4 points[]; };
layout(std430, binding = 1) readonly buffer Sources { vec4 sources[]; };
layout(std430, binding = 2) readonly buffer Strengths { vec2 q[]; };
layout(std430, binding = 3) writeonly buffer Pressure { vec2 pressure[]; };

layout(push_constant) uniform Push {
  uint n_points;
  uint n_sources;
  float k;
} pc;

void main() {
  const uint j = gl_GlobalInvocationID.x;
  if (j >= pc.n_points) return;
  const vec3 x = points[j].xyz;
  vec2 p = vec2(0.0);
  for (uint s = 0; s < pc.n_sources; ++s) {
    const float r = length(x - sources[s].xyz);
    p += cmul(q[s], cis(pc.k * r)) / r;
  }
  pressure[j] = p / (4.0 * kPi);
}
