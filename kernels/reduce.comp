#version 450
// Sums rows of partial outputs: rows [0, rows) of `count` floats starting at src_offset are summed
// in chunks of `chunk` rows into ceil(rows / chunk) rows at dst_offset, or into `result` when
// final != 0 (then rows <= chunk). Called repeatedly until one row remains.
layout(local_size_x = 64) in;

layout(std430, binding = 0) buffer Scratch { float scratch[]; };
layout(std430, binding = 1) writeonly buffer Result { float result[]; };

layout(push_constant) uniform Push {
  uint src_offset;
  uint dst_offset;
  uint rows;
  uint count;
  uint chunk;
  uint final_pass;
} pc;

void main() {
  const uint gid = gl_GlobalInvocationID.x;
  const uint i = gid % pc.count;
  const uint c = gid / pc.count;
  const uint first = c * pc.chunk;
  if (first >= pc.rows) return;
  const uint last = min(first + pc.chunk, pc.rows);
  float s = 0.0;
  for (uint r = first; r < last; ++r) s += scratch[pc.src_offset + r * pc.count + i];
  if (pc.final_pass != 0) result[i] = s;
  else scratch[pc.dst_offset + c * pc.count + i] = s;
}
