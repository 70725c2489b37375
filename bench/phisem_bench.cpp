// PhISEM speed (docs/PERFORMANCE.md, "Particle sounds"): two loads, kept busy by
// shaking every voice 8 times a second, on the CPU (excitation and filterbank) and on the GPU
// (excitation kernel + filterbank in one submit per block):
//   shakers   1,000 voices x 4 resonances (sleigh-bell tuning, retuned after collisions)
//   objects   100 voices x a 1,000-mode object, contacts moving on every shake
// The 1,000-mode object is synthetic (log-spaced modes 60 Hz-16 kHz, random mode shapes at 256
// surface points): the runtime's cost depends on the counts, not on where the modes came from.
// Reports wall time per 256-frame block (median, 99th percentile) against the block's 5.33 ms.
// Usage: chladni_phisem_bench [--seconds S] [--backend cpu,gpu] [--threads N]
//                            [--isa auto|scalar|avx2|avx512] [--json OUT]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "bench_support.hpp"
#include "chladni/core/random.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/filterbank/make_filterbank.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "chladni/runtime/scene/render.hpp"
#include "synthetic_object.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {

constexpr double kFs = 48000;
constexpr uint32_t kBlock = 256;

struct Result {
  std::string load, backend, device;
  uint32_t voices = 0, slots = 0;
  double p50 = 0, p99 = 0, realtime = 0, device_ms = 0;
};

Result run(const std::string& load, const std::string& backend, Filterbank& fb,
           const std::vector<ShakerVoice>& voices, double seconds, int threads) {
  ShakerBankOptions o;
  o.sample_rate = kFs;
  o.max_voices = static_cast<uint32_t>(voices.size());
  o.max_shakes = 8192;
  o.excitation = backend == "gpu" ? ExcitationBackend::Gpu : ExcitationBackend::Cpu;
  o.threads = threads;
  ShakerBank bank(fb, o);
  for (const auto& v : voices) bank.add_voice(v);
  const auto shakes = regular_shakes(bank.voice_count(), 8.0, seconds + 1.0, 0.5f);
  std::vector<float> out(std::size_t(kBlock) * fb.channels());
  std::vector<double> ms, dev;
  std::size_t next = 0;
  const uint64_t blocks = static_cast<uint64_t>(seconds * kFs / kBlock);
  double total = 0;
  for (uint64_t b = 0; b < blocks + 20; ++b) {  // the first 20 blocks warm up
    const uint64_t t = b * kBlock;
    for (; next < shakes.size() && shakes[next].time * kFs < double(t + kBlock); ++next)
      bank.shake(shakes[next].voice, shakes[next].amount,
                 static_cast<uint32_t>(std::max(0.0, std::round(shakes[next].time * kFs) - t)));
    const auto t0 = std::chrono::steady_clock::now();
    bank.render(kBlock, out.data());
    const double dt =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (b >= 20) {
      ms.push_back(dt);
      dev.push_back(fb.last_timing().gpu_ms);
      total += dt;
    }
  }
  std::sort(ms.begin(), ms.end());
  std::sort(dev.begin(), dev.end());
  Result r;
  r.load = load;
  r.backend = backend;
  r.device = fb.name();
  r.voices = bank.voice_count();
  r.slots = bank.slot_end();
  r.p50 = ms[ms.size() / 2];
  r.p99 = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
  r.realtime = (double(ms.size()) * kBlock / kFs) / (total * 1e-3);
  r.device_ms = dev[dev.size() / 2];
  return r;
}

struct Args {
  double seconds = 3;
  int threads = 0;
  std::string json, backends = "cpu,gpu", isa = "auto";
};

// Throws std::invalid_argument with the message to print.
Args parse_args(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seconds"))
      a.seconds = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--threads"))
      a.threads = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--backend"))
      a.backends = argv[i + 1];
    else if (!std::strcmp(argv[i], "--isa"))
      a.isa = argv[i + 1];
    else if (!std::strcmp(argv[i], "--json"))
      a.json = argv[i + 1];
    else
      throw std::invalid_argument(std::string("unknown option ") + argv[i]);
  }
  if (!(a.seconds > 0)) throw std::invalid_argument("--seconds must be > 0");
  const CpuIsa isa = parse_cpu_isa(a.isa);
  if (!CpuFilterbank::supports(isa))
    throw std::invalid_argument("this processor cannot run --isa " + a.isa);
  return a;
}

// A filterbank for `voices` on `backend`; null where there is no Vulkan device.
std::unique_ptr<Filterbank> make_filterbank(const std::string& backend, const Args& a,
                                            const std::vector<ShakerVoice>& voices) {
  FilterbankRequest r;
  r.backend = backend == "gpu" ? gpu::DeviceChoice::Gpu : gpu::DeviceChoice::Cpu;
  r.gpu_falls_back = false;
  for (const auto& v : voices) r.capacity += static_cast<uint32_t>(v.resonances.size());
  r.threads = a.threads;
  r.isa = parse_cpu_isa(a.isa);
  r.max_frames = kBlock;
  r.max_streams = static_cast<uint32_t>(voices.size());
  try {
    return chladni::runtime::make_filterbank(r);
  } catch (const gpu::NoDeviceError& e) {
    std::fprintf(stderr, "gpu: %s; skipped\n", e.what());
    return nullptr;
  }
}

void write_json(const std::string& path, const std::vector<Result>& results) {
  nlohmann::json j = nlohmann::json::array();
  for (const Result& r : results)
    j.push_back({{"load", r.load},
                 {"backend", r.backend},
                 {"device", r.device},
                 {"voices", r.voices},
                 {"slots", r.slots},
                 {"block_frames", kBlock},
                 {"block_ms_p50", r.p50},
                 {"block_ms_p99", r.p99},
                 {"device_ms_p50", r.device_ms},
                 {"realtime_factor", r.realtime}});
  std::ofstream(path) << j.dump(2) << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = bench::parse_or_exit(parse_args, argc, argv);
  // Load 1: 1,000 voices of four retuned resonances.
  PhisemPreset bells = phisem_preset("sleighbells");
  bells.resonances.resize(4);
  std::vector<ShakerVoice> shakers(1000, instrument_voice(bells, kFs));
  // Load 2: 100 voices of gravel on a 1,000-mode object.
  const ModalModel model = bench::synthetic_object(1000, 256);
  const ObjectModes object = object_modes(model);
  std::vector<ShakerVoice> objects;
  for (int v = 0; v < 100; ++v)
    objects.push_back(object_voice(phisem_preset("gravel"), object, kFs, 1e-3, 16, v + 1));

  std::vector<Result> results;
  std::stringstream ss(args.backends);
  for (std::string backend; std::getline(ss, backend, ',');) {
    for (int load = 0; load < 2; ++load) {
      const auto& voices = load == 0 ? shakers : objects;
      const std::unique_ptr<Filterbank> fb = make_filterbank(backend, args, voices);
      if (!fb) break;
      results.push_back(run(load == 0 ? "1000 voices x 4 resonances" : "100 voices x 1000 modes",
                            backend, *fb, voices, args.seconds, args.threads));
      const Result& r = results.back();
      std::printf(
          "%-28s %-4s %6u slots  block p50 %7.3f ms  p99 %7.3f ms  device %7.3f ms  %6.1fx real "
          "time  %s\n",
          r.load.c_str(), r.backend.c_str(), r.slots, r.p50, r.p99, r.device_ms, r.realtime,
          r.device.c_str());
    }
  }
  if (!args.json.empty()) write_json(args.json, results);
  return 0;
}
