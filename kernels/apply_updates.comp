#version 450
// Applies host-side slot changes before a filterbank dispatch: (re)initialise a mode's pole and
// state, and/or set its channel gains. At most one entry per slot per batch (the host merges).
layout(local_size_x = 64) in;

struct Update {
  uvec4 head;  // slot, flags (1: pole+state, 2: gains), gain0 bits, gain1 bits
  vec4 pz;     // p.re, p.im, z.re, z.im
};

layout(std430, binding = 0) buffer Modes { vec4 modes[]; };
layout(std430, binding = 1) buffer Gains { vec2 gains[]; };
layout(std430, binding = 2) readonly buffer Updates { Update updates[]; };

layout(push_constant) uniform Push { uint count; } pc;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= pc.count) return;
  const Update u = updates[i];
  if ((u.head.y & 1u) != 0u) modes[u.head.x] = u.pz;
  if ((u.head.y & 2u) != 0u) gains[u.head.x] = uintBitsToFloat(u.head.zw);
}
