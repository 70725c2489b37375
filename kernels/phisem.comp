#version 450
// PhISEM excitation (runtime/phisem.hpp, Cook 1997): one invocation per voice makes a block of
// its stochastic excitation into the filterbank's input rows. The same counter-based random
// numbers and the same float operations as phisem_generate(), `precise` so that no compiler
// fuses them: the CPU and the GPU make identical samples for a seed.
layout(local_size_x = 64) in;

struct Params {
  float system_decay, sound_decay, probability, gain;
  float eq0, eq1, eq2, pad;
};
struct State {
  float energy, level, x1, x2;
  uint key, counter, collisions, pad;
};

layout(std430, binding = 0) readonly buffer ParamsBuf { Params params[]; };
layout(std430, binding = 1) buffer StateBuf { State states[]; };
layout(std430, binding = 2) readonly buffer Shakes { uvec4 shakes[]; };  // voice, offset, amount
layout(std430, binding = 3) writeonly buffer Inputs { float inputs[]; };

layout(push_constant) uniform Push {
  uint voices;
  uint frames;
  uint shake_count;
  uint pad;
} pc;

const float MIN_ENERGY = 0.001;

uint pcg_hash(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

void main() {
  const uint v = gl_GlobalInvocationID.x;
  if (v >= pc.voices) return;
  const Params p = params[v];
  State st = states[v];
  precise float energy = st.energy, level = st.level, x1 = st.x1, x2 = st.x2;
  uint collisions = st.collisions;
  // This voice's shakes: the list is sorted by (voice, offset).
  uint lo = 0, hi = pc.shake_count;
  while (lo < hi) {
    const uint mid = (lo + hi) >> 1;
    if (shakes[mid].x < v) lo = mid + 1; else hi = mid;
  }
  uint next = lo;
  const uint row = v * pc.frames;
  const bool shaken = next < pc.shake_count && shakes[next].x == v;
  if (!shaken && st.energy == 0.0 && st.level == 0.0 && st.x1 == 0.0 && st.x2 == 0.0) {
    for (uint n = 0; n < pc.frames; ++n) inputs[row + n] = 0.0;  // silent stays silent
    states[v].counter = st.counter + pc.frames;
    return;
  }
  for (uint n = 0; n < pc.frames; ++n) {
    while (next < pc.shake_count && shakes[next].x == v && shakes[next].y == n) {
      energy = min(1.0, energy + uintBitsToFloat(shakes[next].z));
      ++next;
    }
    const uint h = pcg_hash(st.counter + n) ^ st.key;
    if (energy >= MIN_ENERGY) {
      energy = energy * p.system_decay;
      if (float(pcg_hash(h) >> 8) * (1.0 / 16777216.0) < p.probability) {
        level = level + energy;
        ++collisions;
      }
    } else {
      energy = 0.0;
    }
    precise float noise = float(pcg_hash(h ^ 0x85ebca6bu) >> 8) * (2.0 / 16777216.0) - 1.0;
    precise float x = level * noise;
    level = level * p.sound_decay;
    if (level < 1e-20) level = 0.0;
    precise float y = p.eq0 * x + p.eq1 * x1 + p.eq2 * x2;
    x2 = x1;
    x1 = x;
    inputs[row + n] = p.gain * y;
  }
  st.energy = energy;
  st.level = level;
  st.x1 = x1;
  st.x2 = x2;
  st.collisions = collisions;
  st.counter += pc.frames;
  states[v] = st;
}
