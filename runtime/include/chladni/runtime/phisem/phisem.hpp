#pragma once
// PhISEM, Physically Informed Stochastic Event Modeling (P. Cook, "Physically Informed Sonic
// Modeling (PhISM): Synthesis of Percussive Sounds", Computer Music Journal 21:3, 1997, and
// his per-sample code for it). Per sample:
//   energy *= system_decay                    (the shaken system loses energy)
//   if (u < N / 1024)  level += energy         (a collision, likelier with more particles)
//   x = level * noise;  level *= sound_decay    (each collision: a fast-decaying noise burst)
// and x, through a short FIR (the instrument's equalization), drives the system's resonances.
// Shakes put energy back. The excitation x is what this file makes; the resonances are filterbank
// slots driven by it (shaker_bank.hpp), so they can be an instrument's few resonances or the
// modes of a precomputed soundbank.
//
// Random numbers are counter-based (a PCG hash of a per-voice key and the sample index) and the
// arithmetic is plain float with no contraction, so kernels/phisem.comp makes the same samples.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace chladni::runtime {

/// Rate at which the presets' per-sample constants were tuned (STK's default); other rates
/// convert them so that times, rates and bandwidths stay the same.
constexpr double kPhisemReferenceRate = 44100.0;
/// Below this system energy collisions stop (STK's MIN_ENERGY).
constexpr float kPhisemMinEnergy = 0.001f;

struct PhisemResonance {
  double frequency = 0;  ///< Hz
  double radius = 0;     ///< pole radius per reference sample (bandwidth)
  double gain = 1;
  bool vary = false;  ///< retuned at random when particles collide (bells, chimes, drops)
};

struct PhisemPreset {
  std::string name;    ///< CLI name
  std::string title;   ///< what it models
  std::string source;  ///< where the parameters come from
  double objects = 0;  ///< particle count N: collision probability N / 1024 per reference sample
  double system_decay = 0;  ///< energy factor per reference sample
  double sound_decay = 0;   ///< sound-level factor per reference sample
  double gain = 1;          ///< base gain; the excitation is scaled by log(N) gain / N (STK)
  double vary = 0;          ///< relative spread of retuned resonances
  double sweep = 1;         ///< frequency factor per reference sample of retuned resonances (drops)
  std::array<double, 3> eq{1, 0, 0};  ///< FIR b0 + b1 z^-1 + b2 z^-2 on the excitation
  std::vector<PhisemResonance> resonances;
};

/// The instruments: maraca, cabasa, sekere, tambourine, sleighbells, bamboo, water (drops, rain),
/// coins (in a jar), paper (crumple bursts), sandpaper, can, sticks, crunch, gravel, pebbles.
const std::vector<PhisemPreset>& phisem_presets();
/// Throws InputError naming the known instruments.
const PhisemPreset& phisem_preset(std::string_view name);

/// The excitation's per-sample constants at one sample rate.
struct PhisemParams {
  float system_decay = 0;
  float sound_decay = 0;
  float collision_probability = 0;  ///< per sample
  float gain = 0;                   ///< log(N) gain / N
  float eq[3] = {1, 0, 0};
  float pad = 0;  ///< layout shared with kernels/phisem.comp (8 x 32 bits)
};

/// Converts a preset to `sample_rate`; `objects` > 0 replaces its particle count. Throws
/// InputError for a non-finite or out-of-range value.
PhisemParams phisem_params(const PhisemPreset& preset, double sample_rate, double objects = 0);

/// One voice's excitation state. Layout shared with kernels/phisem.comp (8 x 32 bits).
struct PhisemState {
  float energy = 0, level = 0, x1 = 0, x2 = 0;
  uint32_t key = 0;         ///< random stream of this voice
  uint32_t counter = 0;     ///< samples made so far (the random counter)
  uint32_t collisions = 0;  ///< collisions so far (wraps)
  uint32_t pad = 0;
};

/// Energy put into a voice at sample `offset` of a block: energy = min(1, energy + amount).
struct Shake {
  uint32_t voice = 0;
  uint32_t offset = 0;
  float amount = 0;
};

/// The random key of voice `index` for a run seeded with `seed`.
uint32_t phisem_key(uint64_t seed, uint32_t index);

/// Makes `frames` samples of excitation into `out`. `shakes` are this voice's, sorted by offset.
void phisem_generate(const PhisemParams& params, PhisemState& state, std::span<const Shake> shakes,
                     uint32_t frames, float* out);

/// A collision of one shake: its sample and the system energy it adds to the sound level.
struct PhisemCollision {
  uint32_t sample = 0;
  float energy = 0;
};

/// The collisions that one shake of `amount` from rest makes, until the energy falls below
/// kPhisemMinEnergy: the same decisions phisem_generate() takes for this key. Paper crumple
/// bursts of the sound database are one shake of the "paper" instrument.
std::vector<PhisemCollision> phisem_collisions(const PhisemParams& params, uint32_t key,
                                               float amount);

/// The PCG hash (Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 2020), as in GLSL.
inline uint32_t pcg_hash(uint32_t v) {
  const uint32_t state = v * 747796405u + 2891336453u;
  const uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}
/// Uniform in [0, 1) with 24 bits, exact in float.
inline float unit_float(uint32_t h) {
  return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

}  // namespace chladni::runtime
