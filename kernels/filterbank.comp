#version 450
// Modal filterbank (DESIGN.md): every mode is a complex one-pole resonator
//   z[n] = p * z[n-1] + e[n],   p = exp((-d + i*omega_d) / fs),
// and channel c of the output is sum_modes gain_c * Im(z[n]).
// Each invocation advances MPI modes through `samples` samples; per sample the mode sum is
// reduced across the subgroup and one row of partial sums per subgroup is written; reduce.comp
// sums the rows. Excitations are sample-accurate: entries (slot, offset, re, im) sorted by slot,
// then offset, are added right after the pole multiplication at their offset.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint MPI = 4;       // modes per invocation
layout(constant_id = 2) const uint CHANNELS = 1;  // 1 or 2
layout(constant_id = 3) const uint ROWS_PER_GROUP = 8;

layout(std430, binding = 0) buffer Modes { vec4 modes[]; };  // (p.re, p.im, z.re, z.im)
layout(std430, binding = 1) readonly buffer Gains { vec2 gains[]; };
layout(std430, binding = 2) readonly buffer Excitations { uvec4 exc[]; };
layout(std430, binding = 3) writeonly buffer Partials { float partial[]; };

layout(push_constant) uniform Push {
  uint mode_count;  // slots [0, mode_count) are processed
  uint samples;
  uint exc_count;
  uint pad;
} pc;

const uint NONE = 0xffffffffu;

// First index in [0, exc_count) whose slot is >= slot.
uint lower_bound(uint slot) {
  uint lo = 0, hi = pc.exc_count;
  while (lo < hi) {
    uint mid = (lo + hi) >> 1;
    if (exc[mid].x < slot) lo = mid + 1; else hi = mid;
  }
  return lo;
}

void main() {
  const uint lid = gl_LocalInvocationID.x;
  const uint group_modes = gl_WorkGroupSize.x * MPI;
  const uint base = gl_WorkGroupID.x * group_modes;

  vec2 p[MPI], z[MPI], g[MPI];
  uint slot[MPI], next[MPI], stop[MPI];
  uint next_n = NONE;
  for (uint j = 0; j < MPI; ++j) {
    slot[j] = base + j * gl_WorkGroupSize.x + lid;  // coalesced across the workgroup
    p[j] = vec2(0.0); z[j] = vec2(0.0); g[j] = vec2(0.0);
    next[j] = 0; stop[j] = 0;
    if (slot[j] < pc.mode_count) {
      vec4 m = modes[slot[j]];
      p[j] = m.xy; z[j] = m.zw; g[j] = gains[slot[j]];
      if (pc.exc_count > 0) {
        next[j] = lower_bound(slot[j]);
        stop[j] = lower_bound(slot[j] + 1);
        if (next[j] < stop[j]) next_n = min(next_n, exc[next[j]].y);
      }
    }
  }

  const uint row = gl_WorkGroupID.x * ROWS_PER_GROUP + gl_SubgroupID;
  for (uint n = 0; n < pc.samples; ++n) {
    for (uint j = 0; j < MPI; ++j) {
      z[j] = vec2(p[j].x * z[j].x - p[j].y * z[j].y, p[j].x * z[j].y + p[j].y * z[j].x);
    }
    if (n == next_n) {
      next_n = NONE;
      for (uint j = 0; j < MPI; ++j) {
        while (next[j] < stop[j] && exc[next[j]].y == n) {
          z[j] += uintBitsToFloat(exc[next[j]].zw);
          ++next[j];
        }
        if (next[j] < stop[j]) next_n = min(next_n, exc[next[j]].y);
      }
    }
    float left = 0.0, right = 0.0;
    for (uint j = 0; j < MPI; ++j) {
      left += g[j].x * z[j].y;
      if (CHANNELS == 2) right += g[j].y * z[j].y;
    }
    left = subgroupAdd(left);
    if (CHANNELS == 2) right = subgroupAdd(right);
    if (subgroupElect()) {
      partial[(row * pc.samples + n) * CHANNELS] = left;
      if (CHANNELS == 2) partial[(row * pc.samples + n) * CHANNELS + 1] = right;
    }
  }

  for (uint j = 0; j < MPI; ++j) {
    if (slot[j] < pc.mode_count) {
      // Flush states far below audibility: no denormal guarantee on every device.
      if (dot(z[j], z[j]) < 1e-30) z[j] = vec2(0.0);
      modes[slot[j]] = vec4(p[j], z[j]);
    }
  }
}
