// chladni bench: filterbank throughput and per-block latency, CPU and GPU side by side.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <sstream>
#include <thread>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "commands.hpp"
#include "parse_choices.hpp"

namespace chladni::cli {
namespace {

struct BenchArgs {
  std::string modes = "1000,10000,100000,1000000", backends = "cpu,gpu", json_path;
  int threads = 0;
  uint32_t block = 256, batch = 8;
  double sample_rate = 48000, seconds = 1.0;
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t k =
      std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(q * v.size())) - 1);
  return v[k];
}

struct Record {
  std::string backend, device;
  uint32_t modes;
  int threads;
  double mode_samples_per_s, realtime_modes, block_ms_p50, block_ms_p99, gpu_block_ms_p50;
  uint32_t block, batch;
};

// Times calls of `frames` frames until `seconds` have passed (at least `min_calls`).
std::vector<double> time_calls(runtime::Filterbank& fb, uint32_t frames, double seconds,
                               int min_calls, std::vector<float>& out,
                               std::vector<double>* gpu_ms) {
  using clock = std::chrono::steady_clock;
  std::vector<double> ms;
  const auto start = clock::now();
  for (int i = 0; i < 3; ++i) fb.process({}, frames, out.data());  // warm up
  while (static_cast<int>(ms.size()) < min_calls ||
         std::chrono::duration<double>(clock::now() - start).count() < seconds) {
    const auto t0 = clock::now();
    fb.process({}, frames, out.data());
    ms.push_back(std::chrono::duration<double, std::milli>(clock::now() - t0).count());
    if (gpu_ms) gpu_ms->push_back(fb.last_timing().gpu_ms);
    if (ms.size() > 100000) break;
  }
  return ms;
}

Record measure(const BenchArgs& a, const std::string& backend, uint32_t n) {
  runtime::FilterbankRequest req;
  req.capacity = n;
  req.channels = 1;
  req.threads = a.threads;
  req.max_frames = a.block * std::max(1u, a.batch);
  auto fb = make_filterbank(backend, req);
  // Modes spread over the audible band with decays of 0.5-20 1/s, all ringing.
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> logf(std::log(40.0), std::log(18000.0)), dec(0.5, 20.0);
  std::vector<runtime::Excitation> kick;
  for (uint32_t s = 0; s < n; ++s) {
    const double f = std::exp(logf(rng));
    const float g[2] = {1.0f / std::sqrt(float(n)), 0.0f};
    fb->set_mode(s, runtime::pole(2 * std::numbers::pi * f, dec(rng), a.sample_rate), g);
    kick.push_back({s, 0, 1.0f, 0.0f});
  }
  fb->set_high_water(n);
  const uint32_t batch_frames = std::min(fb->max_frames(), a.block * std::max(1u, a.batch));
  std::vector<float> out(std::max(batch_frames, a.block));
  // Excite in chunks the filterbank accepts.
  for (std::size_t k = 0; k < kick.size(); k += fb->max_excitations()) {
    const std::size_t len = std::min<std::size_t>(fb->max_excitations(), kick.size() - k);
    fb->process(std::span(kick.data() + k, len), a.block, out.data());
  }
  std::vector<double> gpu_ms;
  const std::vector<double> lat = time_calls(*fb, a.block, a.seconds, 20, out, &gpu_ms);
  const std::vector<double> thr = time_calls(*fb, batch_frames, a.seconds, 5, out, nullptr);
  double total_ms = 0;
  for (double x : thr) total_ms += x;
  Record r;
  r.backend = fb->name().rfind("gpu", 0) == 0 ? "gpu" : "cpu";
  r.device = fb->name();
  r.modes = n;
  r.threads = a.threads > 0 ? a.threads : static_cast<int>(std::thread::hardware_concurrency());
  r.mode_samples_per_s = double(n) * batch_frames * thr.size() / (total_ms * 1e-3);
  r.realtime_modes = std::floor(r.mode_samples_per_s / a.sample_rate);
  r.block_ms_p50 = percentile(lat, 0.50);
  r.block_ms_p99 = percentile(lat, 0.99);
  r.gpu_block_ms_p50 = percentile(gpu_ms, 0.50);
  r.block = a.block;
  r.batch = batch_frames / a.block;
  return r;
}

void run_bench(const BenchArgs& a) {
  if (!a.json_path.empty() && a.json_path != "-") check_output_path(a.json_path, "--json");
  std::vector<uint32_t> sizes;
  for (const std::string& s : split(a.modes)) {
    char* end = nullptr;
    const unsigned long v = std::strtoul(s.c_str(), &end, 10);
    if (*end || v == 0 || v > (1ul << 24))
      throw InputError("--modes: '" + s + "' is not a count in [1, 16777216]");
    sizes.push_back(static_cast<uint32_t>(v));
  }
  const std::vector<std::string> backends = split(a.backends);
  for (const std::string& b : backends) {
    if (b != "cpu" && b != "gpu") throw InputError("--backend: unknown backend '" + b + "'");
  }
  std::printf("%-4s %9s %12s %14s %10s %10s %10s  %s\n", "", "modes", "mode-smp/s",
              "realtime modes", "p50 ms", "p99 ms", "gpu ms", "device");
  nlohmann::json out = nlohmann::json::array();
  for (uint32_t n : sizes) {
    for (const std::string& b : backends) {
      const Record r = measure(a, b, n);
      std::printf("%-4s %9u %12.3e %14.0f %10.3f %10.3f %10.3f  %s\n", r.backend.c_str(), r.modes,
                  r.mode_samples_per_s, r.realtime_modes, r.block_ms_p50, r.block_ms_p99,
                  r.gpu_block_ms_p50, r.device.c_str());
      std::fflush(stdout);
      out.push_back({{"backend", r.backend},
                     {"device", r.device},
                     {"modes", r.modes},
                     {"threads", r.threads},
                     {"mode_samples_per_s", r.mode_samples_per_s},
                     {"realtime_modes", r.realtime_modes},
                     {"block_ms_p50", r.block_ms_p50},
                     {"block_ms_p99", r.block_ms_p99},
                     {"gpu_block_ms_p50", r.gpu_block_ms_p50},
                     {"block", r.block},
                     {"batch", r.batch},
                     {"sample_rate", a.sample_rate}});
    }
  }
  if (!a.json_path.empty()) {
    if (a.json_path == "-") {
      std::printf("%s\n", out.dump(2).c_str());
    } else {
      write_file_atomic(a.json_path, out.dump(2) + "\n", "--json");
    }
  }
}

}  // namespace

void add_bench(CLI::App& app) {
  auto a = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand("bench", "Measure filterbank speed, CPU and GPU side by side");
  cmd->add_option("--modes", a->modes, "Comma-separated mode counts")->capture_default_str();
  cmd->add_option("--backend", a->backends, "Comma-separated backends: cpu, gpu")
      ->capture_default_str();
  cmd->add_option("--threads", a->threads, "CPU threads (0: all)")
      ->check(thread_count())
      ->capture_default_str();
  cmd->add_option("--block", a->block, "Frames per block (latency)")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  cmd->add_option("--batch", a->batch, "Blocks per call for the throughput figure")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  cmd->add_option("--seconds", a->seconds, "Minimum time per measurement")
      ->check(finite_above(0, 3600))
      ->capture_default_str();
  cmd->add_option("--json", a->json_path, "Write the records as JSON to FILE ('-': stdout)");
  cmd->callback([a] { run_bench(*a); });
}

}  // namespace chladni::cli
