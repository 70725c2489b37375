// The C API under a game's load: N live objects of M modes, impacts at R per second (Poisson,
// a third with a contact time), the listener moving every 50 ms, rendered block by block as an
// audio callback would. Prints mean, 99th percentile and worst render time per block against
// the block's duration. --pace 1 calls render at each block's real-time deadline, as an audio
// device does (the time between calls is then free for a pipelined GPU's work); --pipeline 0
// makes the GPU backend wait for each block. --churn C has a control thread remove an object and
// spawn another in its place C times a second while the audio plays, timing both calls.
// Usage: chladni_capi_bench [--backend cpu|gpu] [--seconds 60] [--objects 64] [--modes 500]
//                           [--rate 200] [--block 256] [--threads 0] [--pace 0|1]
//                           [--pipeline 0|1] [--churn 0] [--json OUT]
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "chladni/chladni.h"

namespace {

struct Args {
  std::string backend = "cpu", json;
  double seconds = 60, rate = 200, churn = 0;
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
    else if (k == "--churn")
      a.churn = std::stod(v);
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

// The objects: each place's bank and position, and its current handle (the churn thread
// replaces it while the game reads it).
struct Objects {
  std::vector<chladni_bank> banks;
  std::vector<std::array<double, 3>> at;
  std::unique_ptr<std::atomic<uint64_t>[]> ids;
  std::size_t size() const { return banks.size(); }
};

// Each object: modes from 80 Hz up, log-spaced to 16 kHz, decays 2-40 /s.
bool spawn_objects(chladni_runtime* rt, const Args& a, std::mt19937& rng, Objects& o) {
  std::uniform_real_distribution<double> u(0, 1);
  o.ids = std::make_unique<std::atomic<uint64_t>[]>(a.objects);
  for (uint32_t k = 0; k < a.objects; ++k) {
    std::vector<double> hz(a.modes), decay(a.modes), amp(a.modes);
    const double f0 = 80 * (1 + 0.3 * u(rng));
    for (uint32_t i = 0; i < a.modes; ++i) {
      hz[i] = f0 * std::pow(16000 / f0, double(i) / a.modes);
      decay[i] = 2 + 38 * u(rng);
      amp[i] = 0.01 / (1 + i * 0.05);
    }
    chladni_bank bank = {0};
    if (!ok(chladni_bank_from_modes(rt, hz.data(), decay.data(), amp.data(), a.modes, &bank),
            "bank"))
      return false;
    o.banks.push_back(bank);
    o.at.push_back({4 * u(rng) - 2, 1 + 3 * u(rng), 0});
    const double q[4] = {1, 0, 0, 0};
    chladni_object id{0};
    if (!ok(chladni_object_spawn(rt, bank, o.at.back().data(), q, 1.0, &id), "spawn")) return false;
    o.ids[k].store(id.id);
  }
  return true;
}

// A control thread replacing objects while the audio plays: each step removes one object and
// spawns a new one of the same bank in its place, timing both calls.
struct Churn {
  std::vector<double> spawn_us, remove_us;
  uint64_t refused = 0;
  std::atomic<bool> running{true};

  void run(chladni_runtime* rt, Objects& o, double rate) {
    using clock = std::chrono::steady_clock;
    const auto period =
        std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(1.0 / rate));
    const double q[4] = {1, 0, 0, 0};
    auto next = clock::now();
    for (std::size_t n = 0; running.load(); ++n) {
      next += period;
      std::this_thread::sleep_until(next);
      const std::size_t k = n % o.size();
      const chladni_object old{o.ids[k].exchange(0)};
      auto t0 = clock::now();
      if (old.id) chladni_object_remove(rt, old);
      remove_us.push_back(std::chrono::duration<double, std::micro>(clock::now() - t0).count());
      chladni_object fresh{0};
      t0 = clock::now();
      const chladni_status s = chladni_object_spawn(rt, o.banks[k], o.at[k].data(), q, 1.0, &fresh);
      spawn_us.push_back(std::chrono::duration<double, std::micro>(clock::now() - t0).count());
      if (s == CHLADNI_OK)
        o.ids[k].store(fresh.id);
      else
        ++refused;  // every place alive or fading: the audio thread is behind
    }
  }
};

// Mean, 99th percentile and worst of `v`.
std::array<double, 3> spread(std::vector<double> v) {
  if (v.empty()) return {0, 0, 0};
  std::sort(v.begin(), v.end());
  double mean = 0;
  for (double x : v) mean += x;
  return {mean / double(v.size()), v[v.size() * 99 / 100], v.back()};
}

// The game thread's posts: Poisson impacts and a listener moving every 50 ms.
struct Game {
  std::mt19937 rng{7};
  std::uniform_real_distribution<double> u{0, 1};
  std::exponential_distribution<double> gap;
  double next_hit = 0, next_move = 0;
  uint64_t impacts = 0, full = 0, gone = 0;

  explicit Game(double rate) : gap(rate) {}

  // Everything that falls before `end`.
  void post_until(chladni_runtime* rt, const Objects& objects, double end) {
    for (; next_hit < end; next_hit += gap(rng)) {
      chladni_impact im{};
      im.object = {
          objects.ids[static_cast<std::size_t>(u(rng) * objects.size()) % objects.size()].load()};
      im.time = next_hit;
      im.impulse = 0.005 + 0.01 * u(rng);
      im.direction[2] = -1;
      im.vertex = -1;
      im.contact_time = u(rng) < 1.0 / 3 ? 0.0005 + 0.001 * u(rng) : 0.0;
      const chladni_status s = chladni_impact_post(rt, &im);
      impacts += s == CHLADNI_OK;
      full += s == CHLADNI_QUEUE_FULL;
      gone += s == CHLADNI_INPUT_ERROR;  // replaced by the churn meanwhile
    }
    for (; next_move < end; next_move += 0.05) {
      const double p[3] = {std::sin(next_move), 0, 0}, f[3] = {0, 1, 0}, up[3] = {0, 0, 1};
      chladni_listener_set(rt, next_move, p, f, up);
    }
  }
};

void report(chladni_runtime* rt, const Args& a, const Game& g, const Churn& churn,
            const std::vector<double>& ms, double block_s) {
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
      budget, 1e3 * chladni_runtime_latency(rt), a.pace ? ", paced at real time" : "");
  std::printf(
      "render per block: mean %.3f ms, p99 %.3f ms, worst %.3f ms at block %lld (%.1fx real "
      "time on the mean, %llu blocks over budget)\n",
      mean, p99, worst, static_cast<long long>(worst_block), budget / mean,
      static_cast<unsigned long long>(
          std::count_if(ms.begin(), ms.end(), [&](double x) { return x > budget; })));
  const auto spawn = spread(churn.spawn_us), remove = spread(churn.remove_us);
  if (a.churn > 0)
    std::printf(
        "churn: %zu objects replaced (%.0f/s asked; %llu spawns refused, %llu impacts on objects "
        "just removed): spawn mean %.1f us, p99 %.1f us, worst %.1f us; remove mean %.1f us, "
        "p99 %.1f us, worst %.1f us\n",
        churn.spawn_us.size(), a.churn, static_cast<unsigned long long>(churn.refused),
        static_cast<unsigned long long>(g.gone), spawn[0], spawn[1], spawn[2], remove[0], remove[1],
        remove[2]);
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
                      {"latency_ms", 1e3 * chladni_runtime_latency(rt)},
                      {"paced", a.pace != 0},
                      {"impacts", g.impacts},
                      {"churn", a.churn},
                      {"replaced", churn.spawn_us.size()},
                      {"spawn_us", spawn},
                      {"remove_us", remove}};
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
  c.max_objects = a.objects + (a.churn > 0 ? 256 : 0);  // room for those fading out
  c.mode_budget = std::max<uint32_t>(65536, a.objects * a.modes);
  c.gpu_pipeline = a.pipeline;
  chladni_runtime* rt = nullptr;
  if (!ok(chladni_runtime_create(&c, &rt), "create")) return 1;
  Game g(a.rate);
  Objects objects;
  if (!spawn_objects(rt, a, g.rng, objects)) return 1;
  Churn churn;
  std::thread control;
  if (a.churn > 0) control = std::thread([&] { churn.run(rt, objects, a.churn); });
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
    g.post_until(rt, objects, chladni_runtime_time(rt) + block_s);
    const auto t0 = std::chrono::steady_clock::now();
    if (!ok(chladni_runtime_render(rt, out.data(), a.block), "render")) break;
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  churn.running.store(false);
  if (control.joinable()) control.join();
  if (ms.size() < blocks) return 1;
  report(rt, a, g, churn, ms, block_s);
  chladni_runtime_destroy(rt);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "error: %s\n", e.what());
  return 2;
}
