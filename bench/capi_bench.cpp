// The C API under a game's load: N live objects of M modes, impacts at R per second (Poisson,
// a third with a contact time), the listener moving every 50 ms, rendered block by block as an
// audio callback would. Prints mean, 99th percentile and worst render time per block against
// the block's duration. --pace 1 calls render at each block's real-time deadline, as an audio
// device does (the time between calls is then free for a pipelined GPU's work); --pipeline 0
// makes the GPU backend wait for each block.
// Usage: chladni_capi_bench [--backend cpu|gpu] [--seconds 60] [--objects 64] [--modes 500]
//                           [--rate 200] [--block 256] [--threads 0] [--pace 0|1]
//                           [--pipeline 0|1] [--json OUT]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "chladni/chladni.h"

namespace {

struct Args {
  std::string backend = "cpu", json;
  double seconds = 60, rate = 200;
  uint32_t objects = 64, modes = 500, block = 256;
  int threads = 0;
  int pace = 0, pipeline = 1;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--backend")
      a.backend = v;
    else if (k == "--seconds")
      a.seconds = std::stod(v);
    else if (k == "--objects")
      a.objects = static_cast<uint32_t>(std::stoul(v));
    else if (k == "--modes")
      a.modes = static_cast<uint32_t>(std::stoul(v));
    else if (k == "--rate")
      a.rate = std::stod(v);
    else if (k == "--block")
      a.block = static_cast<uint32_t>(std::stoul(v));
    else if (k == "--threads")
      a.threads = std::stoi(v);
    else if (k == "--pace")
      a.pace = std::stoi(v);
    else if (k == "--pipeline")
      a.pipeline = std::stoi(v);
    else if (k == "--json")
      a.json = v;
    else
      throw std::invalid_argument("unknown option " + k);
  }
  return a;
}

bool ok(chladni_status s, const char* what) {
  if (s != CHLADNI_OK) std::fprintf(stderr, "%s: %s\n", what, chladni_last_error());
  return s == CHLADNI_OK;
}

// Each object: modes from 80 Hz up, log-spaced to 16 kHz, decays 2-40 /s.
bool spawn_objects(chladni_runtime* rt, const Args& a, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  for (uint32_t k = 0; k < a.objects; ++k) {
    std::vector<double> hz(a.modes), decay(a.modes), amp(a.modes);
    const double f0 = 80 * (1 + 0.3 * u(rng));
    for (uint32_t i = 0; i < a.modes; ++i) {
      hz[i] = f0 * std::pow(16000 / f0, double(i) / a.modes);
      decay[i] = 2 + 38 * u(rng);
      amp[i] = 0.01 / (1 + i * 0.05);
    }
    chladni_bank* bank = nullptr;
    if (!ok(chladni_bank_from_modes(rt, hz.data(), decay.data(), amp.data(), a.modes, &bank),
            "bank"))
      return false;
    const double at[3] = {4 * u(rng) - 2, 1 + 3 * u(rng), 0}, q[4] = {1, 0, 0, 0};
    uint32_t id = 0;
    if (!ok(chladni_spawn(rt, bank, at, q, 1.0, &id), "spawn")) return false;
  }
  return true;
}

// The game thread's posts: Poisson impacts and a listener moving every 50 ms.
struct Game {
  std::mt19937 rng{7};
  std::uniform_real_distribution<double> u{0, 1};
  std::exponential_distribution<double> gap;
  double next_hit = 0, next_move = 0;
  uint64_t impacts = 0, full = 0;

  explicit Game(double rate) : gap(rate) {}

  // Everything that falls before `end`.
  void post_until(chladni_runtime* rt, const Args& a, double end) {
    for (; next_hit < end; next_hit += gap(rng)) {
      chladni_impact im{};
      im.object = static_cast<uint32_t>(u(rng) * a.objects) % a.objects;
      im.time = next_hit;
      im.impulse = 0.005 + 0.01 * u(rng);
      im.direction[2] = -1;
      im.vertex = -1;
      im.contact_time = u(rng) < 1.0 / 3 ? 0.0005 + 0.001 * u(rng) : 0.0;
      const chladni_status s = chladni_post_impact(rt, &im);
      impacts += s == CHLADNI_OK;
      full += s == CHLADNI_QUEUE_FULL;
    }
    for (; next_move < end; next_move += 0.05) {
      const double p[3] = {std::sin(next_move), 0, 0}, f[3] = {0, 1, 0}, up[3] = {0, 0, 1};
      chladni_post_listener(rt, next_move, p, f, up);
    }
  }
};

void report(chladni_runtime* rt, const Args& a, const Game& g, const std::vector<double>& ms,
            double block_s) {
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  double mean = 0;
  for (double x : ms) mean += x;
  mean /= double(ms.size());
  const double p99 = sorted[sorted.size() * 99 / 100], worst = sorted.back();
  const auto worst_block = std::max_element(ms.begin(), ms.end()) - ms.begin();
  const double budget = 1e3 * block_s;
  std::printf(
      "%s: %u objects x %u modes, %.0f impacts/s (%llu posted, %llu refused: queue full), "
      "block %u (%.2f ms), output latency %.2f ms%s\n",
      chladni_runtime_backend(rt), a.objects, a.modes, a.rate,
      static_cast<unsigned long long>(g.impacts), static_cast<unsigned long long>(g.full), a.block,
      budget, 1e3 * chladni_latency(rt), a.pace ? ", paced at real time" : "");
  std::printf(
      "render per block: mean %.3f ms, p99 %.3f ms, worst %.3f ms at block %lld (%.1fx real "
      "time on the mean, %llu blocks over budget)\n",
      mean, p99, worst, static_cast<long long>(worst_block), budget / mean,
      static_cast<unsigned long long>(
          std::count_if(ms.begin(), ms.end(), [&](double x) { return x > budget; })));
  if (a.json.empty()) return;
  nlohmann::json j = {{"backend", chladni_runtime_backend(rt)},
                      {"objects", a.objects},
                      {"modes", a.modes},
                      {"rate", a.rate},
                      {"block", a.block},
                      {"seconds", a.seconds},
                      {"mean_ms", mean},
                      {"p99_ms", p99},
                      {"worst_ms", worst},
                      {"budget_ms", budget},
                      {"latency_ms", 1e3 * chladni_latency(rt)},
                      {"paced", a.pace != 0},
                      {"impacts", g.impacts}};
  std::ofstream(a.json) << j.dump(2) << "\n";
}

}  // namespace

int main(int argc, char** argv) try {
  const Args a = parse(argc, argv);
  chladni_config c;
  chladni_config_default(&c);
  c.backend = a.backend == "gpu" ? CHLADNI_BACKEND_GPU : CHLADNI_BACKEND_CPU;
  c.block_size = a.block;
  c.threads = a.threads;
  c.max_objects = a.objects;
  c.mode_budget = std::max<uint32_t>(65536, a.objects * a.modes);
  c.gpu_pipeline = a.pipeline;
  chladni_runtime* rt = nullptr;
  if (!ok(chladni_runtime_create(&c, &rt), "create")) return 1;
  Game g(a.rate);
  if (!spawn_objects(rt, a, g.rng)) return 1;
  g.next_hit = g.gap(g.rng);  // after the objects: the same draws as always
  const double fs = c.sample_rate, block_s = a.block / fs;
  const uint64_t blocks = static_cast<uint64_t>(a.seconds / block_s);
  std::vector<float> out(static_cast<std::size_t>(a.block) * c.channels);
  std::vector<double> ms;
  ms.reserve(blocks);
  const auto start = std::chrono::steady_clock::now();
  for (uint64_t b = 0; b < blocks; ++b) {
    if (a.pace)
      std::this_thread::sleep_until(start + std::chrono::duration<double>(double(b) * block_s));
    g.post_until(rt, a, chladni_time(rt) + block_s);
    const auto t0 = std::chrono::steady_clock::now();
    if (!ok(chladni_render(rt, out.data(), a.block), "render")) return 1;
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  report(rt, a, g, ms, block_s);
  chladni_runtime_destroy(rt);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "error: %s\n", e.what());
  return 2;
}
