#version 450
#extension GL_GOOGLE_include_directive : require
// Collocation matrix of the equivalent-source fit (precompute/src/transfer/acoustic_transfer.cpp), column
// major, n_points x n_sources, complex: G(x_p, y_s) = e^(ikr) / (4 pi r), r = |x_p - y_s|, or
// with `neumann` its normal derivative at x_p, dG/dn = G (ik - 1/r) (x_p - y_s).n_p / r.
// One invocation per point; neighbouring invocations write neighbouring entries of a column.
#include "complex_math.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Points { vec4 points[]; };
layout(std430, binding = 1) readonly buffer Normals { vec4 normals[]; };
layout(std430, binding = 2) readonly buffer Sources { vec4 sources[]; };
layout(std430, binding = 3) writeonly buffer Matrix { vec2 matrix[]; };

layout(push_constant) uniform Push {
  uint n_points;
  uint n_sources;
  float k;
  uint neumann;
} pc;

void main() {
  const uint p = gl_GlobalInvocationID.x;
  if (p >= pc.n_points) return;
  const vec3 x = points[p].xyz;
  const vec3 n = normals[p].xyz;
  for (uint s = 0; s < pc.n_sources; ++s) {
    const vec3 d = x - sources[s].xyz;
    const float r = length(d);
    vec2 g = cis(pc.k * r) / (4.0 * kPi * r);
    if (pc.neumann != 0) g = cmul(g, vec2(-1.0 / r, pc.k)) * (dot(d, n) / r);
    matrix[s * pc.n_points + p] = g;
  }
}
