#version 450
// Listener gain of every mode from its multipole expansion (runtime/src/transfer_gains.cpp holds
// the same arithmetic for the CPU): gain = |sum_l [g_l(kr) / g_l(kR)] sum_m a_lm Y_lm|, where
// h_l(x) = e^(ix) g_l(x) and g_l follows the upward recurrence g_(l+1) = (2l+1)/x g_l - g_(l-1);
// both sequences are rescaled together, so the ratio never overflows. One invocation per mode;
// Y_lm of each object's listener direction comes precomputed.
layout(local_size_x = 64) in;

struct Mode {
  float k;
  uint order;
  uint offset;
  uint object;
};
struct Object {
  float r;
  float radius;
  uint y_offset;
  uint pad;
};

layout(std430, binding = 0) readonly buffer Modes { Mode modes[]; };
layout(std430, binding = 1) readonly buffer Coefficients { vec2 a[]; };
layout(std430, binding = 2) readonly buffer Objects { Object objects[]; };
layout(std430, binding = 3) readonly buffer Harmonics { float y[]; };
layout(std430, binding = 4) writeonly buffer Gains { float gain[]; };

layout(push_constant) uniform Push {
  uint mode_count;  // modes of this chunk; their coefficients start this chunk's buffer
  uint first_mode;  // where the chunk's gains go
} pc;

vec2 cmul(vec2 p, vec2 q) { return vec2(p.x * q.x - p.y * q.y, p.x * q.y + p.y * q.x); }
vec2 cdiv(vec2 p, vec2 q) { return cmul(p, vec2(q.x, -q.y)) / dot(q, q); }

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= pc.mode_count) return;
  const Mode m = modes[i];
  const Object o = objects[m.object];
  const float x = m.k * o.r, x0 = m.k * o.radius;
  vec2 g0 = vec2(0.0, -1.0 / x), g1 = vec2(-1.0 / x, -1.0 / (x * x));
  vec2 h0 = vec2(0.0, -1.0 / x0), h1 = vec2(-1.0 / x0, -1.0 / (x0 * x0));
  vec2 p = vec2(0.0);
  const int L = int(m.order);
  for (int l = 0; l <= L; ++l) {
    if (l >= 2) {
      const float f = float(2 * l - 1);
      const vec2 g2 = (f / x) * g1 - g0, h2 = (f / x0) * h1 - h0;
      g0 = g1; g1 = g2; h0 = h1; h1 = h2;
      if (abs(h1.x) + abs(h1.y) > 1e15) { g0 *= 1e-15; g1 *= 1e-15; h0 *= 1e-15; h1 *= 1e-15; }
    }
    const vec2 ratio = l == 0 ? cdiv(g0, h0) : cdiv(g1, h1);
    vec2 s = vec2(0.0);
    const uint base = uint(l * l);
    for (uint k = 0; k <= uint(2 * l); ++k) s += a[m.offset + base + k] * y[o.y_offset + base + k];
    p += cmul(ratio, s);
  }
  gain[pc.first_mode + i] = length(p);
}
