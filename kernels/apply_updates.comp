#version 450
// Applies host-side slot changes before a filterbank dispatch: (re)initialise a mode's pole and
// state, and/or set its channel gains. At most one entry per slot per batch (the host merges).
layout(local_size_x = 64) in;

struct Update {
  uvec4 head;   // slot, flags (1: pole+state, 2: gains, 4: pole only, 8: drive, 16: gains
                // to ramp to), gain bits
  vec4 pz;      // p.re, p.im, z.re, z.im
  uvec4 drive;  // input stream (~0: none), gain re bits, gain im bits, 0
};

layout(std430, binding = 0) buffer Modes { vec4 modes[]; };
layout(std430, binding = 1) buffer Gains { vec2 gains[]; };
layout(std430, binding = 2) readonly buffer Updates { Update updates[]; };
layout(std430, binding = 3) buffer Drives { uvec4 drives[]; };
layout(std430, binding = 4) buffer Targets { vec4 targets[]; };  // target gains, elapsed, 0

layout(push_constant) uniform Push { uint count; uint ramp; } pc;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= pc.count) return;
  const Update u = updates[i];
  if ((u.head.y & 1u) != 0u) modes[u.head.x] = u.pz;
  const vec2 g = uintBitsToFloat(u.head.zw);
  if ((u.head.y & 2u) != 0u) {  // at once: no ramp in flight
    gains[u.head.x] = g;
    targets[u.head.x] = vec4(g, float(pc.ramp), 0.0);
  }
  if ((u.head.y & 16u) != 0u) {  // a ramp to g, from where the current one has got to
    const vec4 t = targets[u.head.x];
    const float w = min(1.0, t.z / float(max(pc.ramp, 1u)));
    gains[u.head.x] += w * (t.xy - gains[u.head.x]);
    targets[u.head.x] = vec4(g, 0.0, 0.0);
  }
  if ((u.head.y & 4u) != 0u) modes[u.head.x].xy = u.pz.xy;
  if ((u.head.y & 8u) != 0u) drives[u.head.x] = u.drive;
}
