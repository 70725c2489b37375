#version 450
#extension GL_GOOGLE_include_directive : require
// Boundary elements (precompute/src/bem_far_row.cpp is the double-precision reference): for rows
// row0 .. row0 + n_rows - 1 of the Burton-Miller system, the centroid-rule entry -K - a D of every
// element j (a = i al) into `entries` (row-major, complex), and per row the far part of the
// right-hand side, sum_j (S + a K')_j q_j, into `rhs`. The diagonal is left 0 (the host writes
// the self term). One invocation per (j, row) for the entries; with `rhs_pass`, one per row.
#include "complex_math.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Centroids { vec4 centre[]; };  // w: area / (4 pi)
layout(std430, binding = 1) readonly buffer Normals { vec4 normal[]; };
layout(std430, binding = 2) readonly buffer Dpdn { vec2 q[]; };
layout(std430, binding = 3) writeonly buffer Entries { vec2 entries[]; };
layout(std430, binding = 4) writeonly buffer Rhs { vec2 rhs[]; };

layout(push_constant) uniform Push {
  uint n;
  uint row0;
  uint n_rows;
  uint rhs_pass;
  float k;
  float al;
} pc;

// (entry, weight) of element j seen from row i.
void kernels(uint i, uint j, out vec2 entry, out vec2 weight) {
  const vec3 r = centre[i].xyz - centre[j].xyz;
  const vec3 nx = normal[i].xyz, ny = normal[j].xyz;
  const float R2 = dot(r, r), R = sqrt(R2), inv2 = 1.0 / R2, kr = pc.k * R;
  const vec2 g = cis(kr) * (centre[j].w / R);
  const float rny = dot(r, ny), rnx = dot(r, nx), nn = dot(nx, ny);
  const vec2 gp = cmul(g, vec2(1.0, -kr)) * inv2;  // G (1 - ikR) / R^2
  const vec2 K = gp * rny, Kp = -gp * rnx;
  const float t = rnx * rny * inv2;
  const vec2 H = cmul(g, vec2(nn - t * (3.0 - kr * kr), (3.0 * t - nn) * kr)) * inv2;
  entry = vec2(-K.x + pc.al * H.y, -K.y - pc.al * H.x);
  weight = vec2(g.x - pc.al * Kp.y, g.y + pc.al * Kp.x);
}

void main() {
  if (pc.rhs_pass != 0) {
    const uint r = gl_GlobalInvocationID.x;
    if (r >= pc.n_rows) return;
    const uint i = pc.row0 + r;
    vec2 sum = vec2(0.0);
    for (uint j = 0; j < pc.n; ++j) {
      if (j == i) continue;
      vec2 entry, weight;
      kernels(i, j, entry, weight);
      sum += cmul(weight, q[j]);
    }
    rhs[r] = sum;
    return;
  }
  const uint j = gl_GlobalInvocationID.x, r = gl_GlobalInvocationID.y;
  if (j >= pc.n || r >= pc.n_rows) return;
  const uint i = pc.row0 + r;
  vec2 entry = vec2(0.0), weight;
  if (j != i) kernels(i, j, entry, weight);
  entries[r * pc.n + j] = entry;
}
