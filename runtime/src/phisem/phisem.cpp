// Built with -ffp-contract=off: kernels/phisem.comp (with `precise`) must round the same way.
#include "chladni/runtime/phisem/phisem.hpp"

#include <algorithm>
#include <cmath>

#include "chladni/core/error.hpp"

namespace chladni::runtime {
namespace {

void check(bool ok, const std::string& what) {
  if (!ok) throw InputError(what);
}

}  // namespace

PhisemParams phisem_params(const PhisemPreset& preset, double fs, double objects) {
  const std::string who = "instrument '" + preset.name + "': ";
  check(std::isfinite(fs) && fs >= 8000 && fs <= 384000,
        who + "sample rate must be 8000-384000 Hz");
  check(std::isfinite(objects) && objects >= 0, who + "particle count must be finite and >= 0");
  const double n = objects > 0 ? objects : preset.objects;
  const double per = kPhisemReferenceRate / fs;  // reference samples per sample
  check(preset.system_decay > 0 && preset.system_decay <= 1,
        who + "system decay must be in (0, 1]");
  check(preset.sound_decay > 0 && preset.sound_decay < 1, who + "sound decay must be in (0, 1)");
  check(std::isfinite(preset.gain), who + "gain must be finite");
  PhisemParams p;
  p.system_decay = static_cast<float>(std::pow(preset.system_decay, per));
  p.sound_decay = static_cast<float>(std::pow(preset.sound_decay, per));
  // Cook's test random(1024) < N, per reference sample, as a probability at this rate.
  p.collision_probability = static_cast<float>(std::min(1.0, n / 1024.0 * per));
  // STK scales by log(N) / N (more particles: each one smaller); N >= 1.1 as in its controls.
  const double nn = std::max(n, 1.1);
  p.gain = static_cast<float>(std::log(nn) * preset.gain / nn);
  for (int k = 0; k < 3; ++k) {
    check(std::isfinite(preset.eq[k]), who + "equalization must be finite");
    p.eq[k] = static_cast<float>(preset.eq[k]);
  }
  return p;
}

uint32_t phisem_key(uint64_t seed, uint32_t index) {
  const uint32_t s =
      pcg_hash(static_cast<uint32_t>(seed) ^ pcg_hash(static_cast<uint32_t>(seed >> 32)));
  return pcg_hash(s ^ pcg_hash(index + 0x9e3779b9u));
}

std::vector<PhisemCollision> phisem_collisions(const PhisemParams& p, uint32_t key, float amount) {
  std::vector<PhisemCollision> out;
  float energy = std::min(1.0f, amount);
  for (uint32_t n = 0; energy >= kPhisemMinEnergy; ++n) {
    const uint32_t h = pcg_hash(n) ^ key;  // counter n: a voice at rest starts at 0
    energy = energy * p.system_decay;
    if (unit_float(pcg_hash(h)) < p.collision_probability) out.push_back({n, energy});
    if (p.system_decay >= 1.0f && n > (1u << 24)) break;  // a system that never loses energy
  }
  return out;
}

void phisem_generate(const PhisemParams& p, PhisemState& st, std::span<const Shake> shakes,
                     uint32_t frames, float* out) {
  if (shakes.empty() && st.energy == 0.0f && st.level == 0.0f && st.x1 == 0.0f && st.x2 == 0.0f) {
    std::fill(out, out + frames, 0.0f);  // a silent voice stays silent (as the loop would)
    st.counter += frames;
    return;
  }
  float energy = st.energy, level = st.level, x1 = st.x1, x2 = st.x2;
  uint32_t collisions = st.collisions;
  std::size_t next = 0;
  for (uint32_t n = 0; n < frames; ++n) {
    for (; next < shakes.size() && shakes[next].offset == n; ++next)
      energy = std::min(1.0f, energy + shakes[next].amount);
    const uint32_t h = pcg_hash(st.counter + n) ^ st.key;
    if (energy >= kPhisemMinEnergy) {
      energy = energy * p.system_decay;                         // exponential system decay
      if (unit_float(pcg_hash(h)) < p.collision_probability) {  // a collision
        level = level + energy;
        ++collisions;
      }
    } else {
      energy = 0.0f;
    }
    // The sound: decaying noise; 24 random bits to [-1, 1) exactly.
    const float noise =
        static_cast<float>(pcg_hash(h ^ 0x85ebca6bu) >> 8) * (2.0f / 16777216.0f) - 1.0f;
    const float x = level * noise;
    level = level * p.sound_decay;
    if (level < 1e-20f) level = 0.0f;  // no denormals in a silent voice
    const float y = p.eq[0] * x + p.eq[1] * x1 + p.eq[2] * x2;
    x2 = x1;
    x1 = x;
    out[n] = p.gain * y;
  }
  st.energy = energy;
  st.level = level;
  st.x1 = x1;
  st.x2 = x2;
  st.collisions = collisions;
  st.counter += frames;
}

}  // namespace chladni::runtime
