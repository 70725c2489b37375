#version 450
// Modal filterbank (DESIGN.md): every mode is a complex one-pole resonator
//   z[n] = p * z[n-1] + e[n],   p = exp((-d + i*omega_d) / fs),
// and channel c of the output is sum_modes gain_c * Im(z[n]).
// Each invocation advances MPI modes through `samples` samples; per sample the mode sum is
// reduced across the subgroup and one row of partial sums per subgroup is written; reduce.comp
// sums the rows. Excitations are sample-accurate: entries (invocation, offset | j << 16, re, im),
// sorted by invocation then offset (the host maps slot -> invocation, j), are added right after
// the pole multiplication at their offset. One list pointer per invocation keeps the hot loop's
// register pressure low (per-mode pointers doubled its cost on lavapipe). Excitations split the
// sample loop into segments so that the hot loop carries no per-sample test; segment bounds are
// subgroup-uniform (subgroupMin) because emit() reduces across the subgroup, which is only
// defined when every invocation of the subgroup is at the same sample.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint MPI = 32;      // modes per invocation
layout(constant_id = 2) const uint CHANNELS = 1;  // 1 or 2
layout(constant_id = 3) const uint ROWS_PER_GROUP = 8;
// Driven slots (stochastic excitation): z[n] = p z[n-1] + a x_k[n], the input term added after
// the pole product as in the CPU reference. A separate pipeline, so undriven banks pay nothing.
layout(constant_id = 4) const bool DRIVEN = false;
// Gain ramps: a mode's gain at sample n is g + w (t - g), w = min(1, (e + n + 1) / ramp), with
// e the samples elapsed since its ramp began (as the CPU reference); a ramp that ends in this
// call leaves its target as the gain.
layout(constant_id = 5) const bool RAMP = false;

layout(std430, binding = 0) buffer Modes { vec4 modes[]; };  // (p.re, p.im, z.re, z.im)
layout(std430, binding = 1) buffer Gains { vec2 gains[]; };
layout(std430, binding = 2) readonly buffer Excitations { uvec4 exc[]; };  // see above
layout(std430, binding = 3) writeonly buffer Partials { float partial[]; };
layout(std430, binding = 4) readonly buffer Drives { uvec4 drive[]; };  // stream, a.re, a.im bits
layout(std430, binding = 5) readonly buffer Inputs { float inputs[]; };  // stream-major rows
layout(std430, binding = 6) buffer Targets { vec4 targets[]; };  // target gains, elapsed, 0

layout(push_constant) uniform Push {
  uint mode_count;  // slots [0, mode_count) are processed
  uint samples;
  uint exc_count;
  uint ramp;  // samples of this call's gain ramp
} pc;

const uint NONE = 0xffffffffu;

float pr[MPI], pi[MPI], zr[MPI], zi[MPI], g0[MPI], g1[MPI];
float ar[DRIVEN ? MPI : 1], ai[DRIVEN ? MPI : 1];
float d0[RAMP ? MPI : 1], d1[RAMP ? MPI : 1], c0[RAMP ? MPI : 1];
uint src[DRIVEN ? MPI : 1];
uint row_base;

// First index in [0, exc_count) whose invocation is >= inv.
uint lower_bound(uint inv) {
  uint lo = 0, hi = pc.exc_count;
  while (lo < hi) {
    uint mid = (lo + hi) >> 1;
    if (exc[mid].x < inv) lo = mid + 1; else hi = mid;
  }
  return lo;
}

// The first sample at which any invocation of the subgroup has an excitation (uniform).
uint next_sample(uint next, uint stop) {
  return subgroupMin(next < stop ? (exc[next].y & 0xffffu) : NONE);
}

// z <- p z (+ a x[n] when driven) for every mode of this invocation.
void step(uint n) {
  // A voice's modes are consecutive slots, so an invocation's modes mostly share a stream: load
  // each stream's sample once (undriven modes have zero gains and read stream NONE as 0).
  uint cur = NONE;
  float x = 0.0;
  for (uint j = 0; j < MPI; ++j) {
    float r = pr[j] * zr[j] - pi[j] * zi[j];
    float i = pr[j] * zi[j] + pi[j] * zr[j];
    if (DRIVEN) {
      if (src[j] != cur && src[j] != NONE) {
        cur = src[j];
        x = inputs[cur * pc.samples + n];
      }
      r += ar[j] * x;
      i += ai[j] * x;
    }
    zr[j] = r;
    zi[j] = i;
  }
}

// Output of sample n: sum of gain * Im(z), over the invocation, then the subgroup.
void emit(uint n) {
  float left = 0.0, right = 0.0;
  if (RAMP) {
    const float inv = 1.0 / float(pc.ramp);
    for (uint j = 0; j < MPI; ++j) {
      const float w = min(1.0, float(n) * inv + c0[j]);
      left += (g0[j] + w * d0[j]) * zi[j];
      if (CHANNELS == 2) right += (g1[j] + w * d1[j]) * zi[j];
    }
  } else {
    for (uint j = 0; j < MPI; ++j) {
      left += g0[j] * zi[j];
      if (CHANNELS == 2) right += g1[j] * zi[j];
    }
  }
  left = subgroupAdd(left);
  if (CHANNELS == 2) right = subgroupAdd(right);
  if (subgroupElect()) {
    partial[(row_base + n) * CHANNELS] = left;
    if (CHANNELS == 2) partial[(row_base + n) * CHANNELS + 1] = right;
  }
}

void main() {
  const uint lid = gl_LocalInvocationID.x;
  const uint base = gl_WorkGroupID.x * gl_WorkGroupSize.x * MPI;
  row_base = (gl_WorkGroupID.x * ROWS_PER_GROUP + gl_SubgroupID) * pc.samples;

  for (uint j = 0; j < MPI; ++j) {
    const uint s = base + j * gl_WorkGroupSize.x + lid;  // coalesced across the workgroup
    pr[j] = 0.0; pi[j] = 0.0; zr[j] = 0.0; zi[j] = 0.0; g0[j] = 0.0; g1[j] = 0.0;
    if (s < pc.mode_count) {
      const vec4 m = modes[s];
      const vec2 g = gains[s];
      pr[j] = m.x; pi[j] = m.y; zr[j] = m.z; zi[j] = m.w; g0[j] = g.x; g1[j] = g.y;
    }
    if (RAMP) {
      d0[j] = 0.0; d1[j] = 0.0; c0[j] = 1.0;
      if (s < pc.mode_count) {
        const vec4 t = targets[s];
        const float inv = 1.0 / float(pc.ramp);
        d0[j] = t.x - g0[j]; d1[j] = t.y - g1[j]; c0[j] = t.z * inv + inv;
      }
    }
    if (DRIVEN) {
      src[j] = NONE; ar[j] = 0.0; ai[j] = 0.0;
      if (s < pc.mode_count) {
        const uvec4 d = drive[s];
        src[j] = d.x; ar[j] = uintBitsToFloat(d.y); ai[j] = uintBitsToFloat(d.z);
      }
    }
  }
  // This invocation's excitations: [next, stop), in offset order.
  const uint inv = gl_GlobalInvocationID.x;
  uint next = 0, stop = 0;
  if (pc.exc_count > 0) {
    next = lower_bound(inv);
    stop = lower_bound(inv + 1);
  }
  uint next_n = next_sample(next, stop);
  uint n = 0;
  while (n < pc.samples) {
    const uint seg_end = min(next_n, pc.samples);
    for (; n < seg_end; ++n) {  // hot loop: no excitation in [n, seg_end)
      step(n);
      emit(n);
    }
    if (n == pc.samples) break;
    // Sample n carries excitations of some invocation of the subgroup.
    step(n);
    while (next < stop && (exc[next].y & 0xffffu) == n) {
      const uint k = exc[next].y >> 16;
      const vec2 e = uintBitsToFloat(exc[next].zw);
      for (uint j = 0; j < MPI; ++j) {  // unrolled select: no dynamic indexing of the state
        if (j == k) { zr[j] += e.x; zi[j] += e.y; }
      }
      ++next;
    }
    next_n = next_sample(next, stop);
    emit(n);
    ++n;
  }

  for (uint j = 0; j < MPI; ++j) {
    const uint s = base + j * gl_WorkGroupSize.x + lid;
    if (s < pc.mode_count) {
      // Flush states far below audibility: no denormal guarantee on every device.
      if (zr[j] * zr[j] + zi[j] * zi[j] < 1e-30) { zr[j] = 0.0; zi[j] = 0.0; }
      modes[s] = vec4(pr[j], pi[j], zr[j], zi[j]);
      if (RAMP) {
        const vec4 t = targets[s];
        const float e = t.z + float(pc.samples);
        if (e >= float(pc.ramp)) {
          gains[s] = t.xy;
          targets[s].z = float(pc.ramp);
        } else {
          targets[s].z = e;
        }
      }
    }
  }
}
