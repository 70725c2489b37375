// Continuous contacts' cost (docs/PERFORMANCE.md, "Continuous contact"): N contacts, each sliding
// and rolling on its own object of M modes with its point moving at a physics rate of 60 Hz,
// rendered in 256-frame blocks on one core. Reports, per block, the contacts' excitation
// (ContactBank::prepare: profiles, fades, drive gains) and the filterbank that rings their modes,
// against the block's 5.33 ms. The objects are synthetic (log-spaced modes 60 Hz-16 kHz, random
// shapes at 256 surface points): the cost depends on the counts, not on where the modes came from.
// Usage: chladni_contact_bench [--contacts N] [--modes M] [--seconds S] [--isa
// auto|scalar|avx2|avx512]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "chladni/core/random.hpp"
#include "chladni/runtime/contact/contact_bank.hpp"
#include "chladni/runtime/filterbank/make_filterbank.hpp"
#include "synthetic_object.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {

constexpr double kFs = 48000;
constexpr uint32_t kBlock = 256;

struct Args {
  uint32_t contacts = 64, modes = 200;
  double seconds = 5;
  std::string isa = "auto";
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 >= argc) throw std::invalid_argument("usage: " + k + " needs a value");
    const std::string v = argv[++i];
    if (k == "--contacts")
      a.contacts = uint32_t(std::stoul(v));
    else if (k == "--modes")
      a.modes = uint32_t(std::stoul(v));
    else if (k == "--seconds")
      a.seconds = std::stod(v);
    else if (k == "--isa")
      a.isa = v;
    else
      throw std::invalid_argument("unknown option " + k);
  }
  if (a.contacts == 0 || a.modes == 0 || !(a.seconds > 0))
    throw std::invalid_argument("--contacts, --modes and --seconds must be > 0");
  return a;
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(q * double(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  const Args a = bench::parse_or_exit(parse, argc, argv);
  const ModalModel model = bench::synthetic_object(a.modes, 256, 5);
  const ObjectModes object = object_modes(model);
  FilterbankRequest r;
  r.capacity = a.contacts * a.modes;
  r.channels = 2;
  r.threads = 1;
  r.isa = parse_cpu_isa(a.isa);
  r.max_frames = kBlock;
  std::unique_ptr<Filterbank> fb = make_filterbank(r);
  ContactBank bank(*fb, {.sample_rate = kFs, .max_contacts = a.contacts});
  const std::vector<float> gains(a.modes, 1e-3f);
  for (uint32_t c = 0; c < a.contacts; ++c) {
    ContactSpec spec;
    spec.bodies[0] = &object;
    spec.roughness = roughness_presets()[c % roughness_presets().size()];
    spec.seed = c + 1;
    bank.add_contact(spec);
    bank.set_gains(int(c), 0, gains, 0.7f, 0.7f);
  }
  const uint64_t step = uint64_t(kFs / 60);  // a physics step
  Rng rng(9);
  uint64_t next_point = 0;
  std::vector<float> rows(std::size_t(a.contacts) * kBlock), out(2 * kBlock);
  std::vector<double> excite_ms, ring_ms;
  const uint64_t blocks = uint64_t(a.seconds * kFs / kBlock);
  for (uint64_t b = 0; b < blocks + 20; ++b) {  // the first 20 blocks warm up
    const uint64_t now = b * kBlock;
    while (next_point <= now + 2 * kBlock) {  // each contact's next physics step
      for (uint32_t c = 0; c < a.contacts; ++c) {
        ContactPoint p;
        p.sample = next_point;
        p.force = float(1 + rng.uniform());
        p.slip = float(0.5 * rng.uniform());
        p.rolling = float(0.5 * rng.uniform());
        p.vertex = {uint32_t(rng.index(256)), 0};
        bank.push(int(c), p);
      }
      next_point += step;
    }
    const auto t0 = bench::clock_type::now();
    bank.render(now, kBlock, rows.data());
    const auto t1 = bench::clock_type::now();
    fb->process({}, kBlock, out.data(), {rows.data(), bank.streams()});
    const double e = std::chrono::duration<double>(t1 - t0).count() * 1e3;
    const double f = bench::seconds_since(t1) * 1e3;
    if (b >= 20) excite_ms.push_back(e), ring_ms.push_back(f);
  }
  const double period = 1e3 * kBlock / kFs;
  std::printf("contacts %u, modes %u each (%u slots), %s, 256-frame blocks (%.2f ms)\n", a.contacts,
              a.modes, a.contacts * a.modes, fb->name().c_str(), period);
  std::printf("excitation: median %.3f ms, p99 %.3f ms a block (%.2f us per contact)\n",
              percentile(excite_ms, 0.5), percentile(excite_ms, 0.99),
              1e3 * percentile(excite_ms, 0.5) / a.contacts);
  std::printf("filterbank: median %.3f ms, p99 %.3f ms a block\n", percentile(ring_ms, 0.5),
              percentile(ring_ms, 0.99));
  std::printf("together: median %.3f ms = %.1f %% of the block\n",
              percentile(excite_ms, 0.5) + percentile(ring_ms, 0.5),
              100 * (percentile(excite_ms, 0.5) + percentile(ring_ms, 0.5)) / period);
  return 0;
}
