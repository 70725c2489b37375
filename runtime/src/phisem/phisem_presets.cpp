// PhISEM instrument parameters. Where the source says STK: Perry Cook's values as shipped in the
// Synthesis ToolKit's Shakers class (STK 4.6.2, Cook and Scavone, 1995-2021), per sample at
// 44.1 kHz; our tests compare against that class.
#include <sstream>

#include "chladni/core/error.hpp"
#include "chladni/runtime/phisem/phisem.hpp"

namespace chladni::runtime {
namespace {

constexpr const char* kStk = "STK 4.6.2 Shakers (P. Cook, PhISEM 1997)";

std::vector<PhisemPreset> make_presets() {
  using R = PhisemResonance;
  std::vector<PhisemPreset> p;
  // name, title, source, N, system decay, sound decay, gain, vary, sweep, eq, resonances
  p.push_back({"maraca",
               "maraca: beans in a gourd",
               kStk,
               25,
               0.999,
               0.95,
               4.0,
               0,
               1,
               {1, -1, 0},
               {R{3200, 0.96, 1.0}}});
  p.push_back({"cabasa",
               "cabasa: beads on a chain around a gourd",
               kStk,
               512,
               0.997,
               0.96,
               8.0,
               0,
               1,
               {1, -1, 0},
               {R{3000, 0.7, 1.0}}});
  p.push_back({"sekere",
               "sekere: beads in a net around a gourd",
               kStk,
               64,
               0.999,
               0.96,
               4.0,
               0,
               1,
               {1, 0, -1},
               {R{5500, 0.6, 1.0}}});
  p.push_back({"tambourine",
               "tambourine: shell and jingles",
               kStk,
               32,
               0.9985,
               0.95,
               1.0,
               0.05,
               1,
               {1, 0, -1},
               {R{2300, 0.96, 0.1}, R{5600, 0.99, 0.8, true}, R{8100, 0.99, 1.0, true}}});
  p.push_back({"sleighbells",
               "sleigh bells",
               kStk,
               32,
               0.9994,
               0.97,
               1.0,
               0.03,
               1,
               {1, 0, -1},
               {R{2500, 0.99, 1.0, true}, R{5300, 0.99, 1.0, true}, R{6500, 0.99, 1.0, true},
                R{8300, 0.99, 0.5, true}, R{9800, 0.99, 0.3, true}}});
  p.push_back({"bamboo",
               "bamboo wind chimes",
               kStk,
               1.2,
               0.9999,
               0.9,
               0.4,
               0.2,
               1,
               {1, 0, 0},
               {R{2800, 0.995, 1.0, true}, R{2240, 0.995, 1.0, true}, R{3360, 0.995, 1.0, true}}});
  // STK's water drops fall at N / 32767 per sample, not N / 1024: N = 10 there is 0.3125 here.
  // Each drop retunes the resonances by +-25% (STK: 0.75, 1 and 1.25 times 600 Hz +-25%) and
  // sweeps them upwards by 1.0001 per sample.
  const std::vector<R> drops = {R{450, 0.9985, 1.0, true}, R{600, 0.9985, 1.0, true},
                                R{750, 0.9985, 1.0, true}};
  p.push_back({"water",
               "water drops",
               std::string(kStk) + ", drop rate and spread as in STK",
               0.3125,
               0.996,
               0.95,
               10.0,
               0.25,
               1.0001,
               {1, 0, -1},
               drops});
  p.push_back({"rain",
               "rain: many drops",
               "STK's water drops at 16x the drop rate (Chladni)",
               5.0,
               0.9995,
               0.95,
               2.0,
               0.3,
               1.0001,
               {1, 0, -1},
               drops});
  p.push_back({"coins",
               "coins shaken in a jar (STK's penny in a mug)",
               kStk,
               3,
               0.9995,
               0.97,
               0.8,
               0,
               1,
               {1, 0, -1},
               {R{2123, 0.997, 1.0}, R{4518, 0.997, 0.8}, R{8856, 0.997, 0.6}, R{10753, 0.997, 0.4},
                R{11000, 0.999, 1.0}, R{5200, 0.999, 0.8}, R{3835, 0.999, 0.5}}});
  // Crisp, short clicks over two broad bands: STK's Crunch1 moved up in frequency towards the
  // crumpling clicks of paper (Schreck et al. 2016); tuned by ear, no measured source.
  p.push_back({"paper",
               "paper crumple bursts",
               "Chladni, from STK's Crunch1",
               12,
               0.9985,
               0.9,
               4.0,
               0.1,
               1,
               {1, -1, 0},
               {R{2500, 0.85, 1.0, true}, R{6000, 0.8, 0.7, true}}});
  p.push_back({"sandpaper",
               "sandpaper",
               kStk,
               128,
               0.999,
               0.999,
               0.5,
               0,
               1,
               {1, 0, -1},
               {R{4500, 0.6, 1.0}}});
  p.push_back({"can",
               "a drink can with something inside",
               kStk,
               48,
               0.999,
               0.97,
               0.5,
               0,
               1,
               {1, 0, -1},
               {R{370, 0.99, 1.0}, R{1025, 0.992, 1.8}, R{1424, 0.992, 1.8}, R{2149, 0.992, 1.8},
                R{3596, 0.992, 1.8}}});
  p.push_back({"sticks",
               "breaking sticks",
               kStk,
               2,
               0.998,
               0.96,
               6.0,
               0,
               1,
               {1, 0, -1},
               {R{5500, 0.6, 1.0}}});
  p.push_back({"crunch",
               "crunchy snow",
               kStk,
               7,
               0.99806,
               0.95,
               4.0,
               0,
               1,
               {1, -1, 0},
               {R{800, 0.95, 1.0}}});
  p.push_back({"gravel",
               "big rocks",
               kStk,
               23,
               0.9965,
               0.98,
               4.0,
               0.11,
               1,
               {1, 0, -1},
               {R{6460, 0.932, 1.0, true}}});
  p.push_back({"pebbles",
               "little rocks",
               kStk,
               1600,
               0.99586,
               0.98,
               4.0,
               0.18,
               1,
               {1, 0, -1},
               {R{9000, 0.843, 1.0, true}}});
  return p;
}

}  // namespace

const std::vector<PhisemPreset>& phisem_presets() {
  static const std::vector<PhisemPreset> presets = make_presets();
  return presets;
}

const PhisemPreset& phisem_preset(std::string_view name) {
  for (const PhisemPreset& p : phisem_presets())
    if (p.name == name) return p;
  std::ostringstream msg;
  msg << "unknown instrument '" << name << "' (known:";
  for (const PhisemPreset& p : phisem_presets()) msg << ' ' << p.name;
  msg << ")";
  throw InputError(msg.str());
}

}  // namespace chladni::runtime
