// Listener-gain updates (docs/PERFORMANCE.md, "Listener gains"): a soundbank's transfer repeated
// over instances until M modes, the listener moved before every update, at several distances.
// Per update: CPU with far-field maps (1 and all threads), CPU series, GPU series; the maps' build
// time and size, and their error against the series in dB.
// Usage: chladni_gains_bench BANK [--gain-modes M] [--distances d1,d2,...] [--json OUT]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "bench_support.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/modal/transfer_gains.hpp"
#include "chladni/runtime/thread_pool.hpp"

using namespace chladni;
using bench::clock_type;
using bench::seconds_since;

namespace {

// The listener for update `rep` of object `o`: distance d (in units of R) about the centre, in a
// direction that turns from update to update and object to object.
Vec3 listener_at(const Transfer& t, double d, int rep, std::size_t o) {
  const double a = 0.37 * rep + 0.11 * double(o), b = 0.23 * rep - 0.07 * double(o);
  return add(
      t.centre,
      scale(Vec3{std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b)}, d * t.radius));
}

template <class F>
double median_ms(F&& fn) {
  std::vector<double> ms;
  for (int rep = 0; rep < 31; ++rep) {
    const auto s = clock_type::now();
    fn(rep);
    ms.push_back(1e3 * seconds_since(s));
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

struct Args {
  std::string bank, json;
  std::vector<double> distances;
  std::size_t gain_modes = 100000;
};

Args parse_args(int argc, char** argv) {
  Args a;
  a.bank = argv[1];
  std::string distances = "3,10,30";
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--gain-modes"))
      a.gain_modes = std::stoul(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--distances"))
      distances = argv[i + 1];
    else if (!std::strcmp(argv[i], "--json"))
      a.json = argv[i + 1];
  }
  std::stringstream ds(distances);
  for (std::string tok; std::getline(ds, tok, ',');) a.distances.push_back(std::stod(tok));
  return a;
}

// The same instances with far-field maps and as series only, until `gain_modes` modes.
struct Tables {
  runtime::TransferTable maps, series;
};

void build_tables(const Args& a, const Transfer& t, runtime::ThreadPool& pool, unsigned hw,
                  Tables& tb, nlohmann::json& j) {
  tb.series.map_options.reset();
  const auto t0 = clock_type::now();
  tb.maps.add(t, &pool);
  const double build_s = seconds_since(t0);
  tb.series.add(t);
  while (tb.maps.mode_count() < a.gain_modes) tb.maps.add_instance(0), tb.series.add_instance(0);
  const runtime::GainMap& m = tb.maps.maps[0];
  std::vector<float> valid = m.valid_radius;
  std::sort(valid.begin(), valid.end());
  const double median_valid = valid[valid.size() / 2] / t.radius;
  std::string grids;
  for (const auto& g : m.grids) {
    char cell[64];  // " rows x cols: modes"
    std::snprintf(cell, sizeof cell, " %ux%u:%zu", unsigned(g.rows), unsigned(g.cols),
                  g.modes.size());
    grids += cell;
  }
  const double per_mode = double(t.coefficients.size()) / double(t.mode_count());
  std::printf(
      "%s: %zu modes per object, R %.3f m; %zu modes in %zu objects, %.0f coefficients per mode\n"
      "maps: %.1f MB, built in %.2f s (%u threads); grids (rows x cols: modes)%s\n"
      "  valid radius: median %.1f R, largest %.1f R; %u of %u modes series-only\n",
      a.bank.c_str(), t.mode_count(), t.radius, tb.maps.mode_count(), tb.maps.objects.size(),
      per_mode, m.bytes() / 1e6, build_s, hw, grids.c_str(), median_valid,
      m.max_valid_radius / t.radius, m.series_modes, m.modes);
  j["modes"] = tb.maps.mode_count();
  j["objects"] = tb.maps.objects.size();
  j["coefficients_per_mode"] = per_mode;
  j["map"] = {{"grids", grids},
              {"megabytes", m.bytes() / 1e6},
              {"build_s", build_s},
              {"series_only_modes", m.series_modes},
              {"median_valid_radius_R", median_valid},
              {"max_valid_radius_R", m.max_valid_radius / t.radius}};
}

// Every object's listener for update `rep` at distance d.
void place(const Transfer& t, double d, int rep, std::vector<Vec3>& at) {
  for (std::size_t o = 0; o < at.size(); ++o) at[o] = listener_at(t, d, rep, o);
}

// Median time per update at distance d: maps on one and on all threads, series, GPU series.
void time_updates(const Transfer& t, double d, Tables& tb, runtime::GpuTransferGains* gpu,
                  const gpu::Context* ctx, runtime::ThreadPool& pool, unsigned hw,
                  nlohmann::json& row) {
  const std::size_t n = tb.maps.mode_count();
  std::vector<Vec3> at(tb.maps.objects.size());
  runtime::ListenerFrame frame;
  std::vector<float> a(n), b(n);
  for (unsigned threads : {1u, hw}) {
    runtime::ThreadPool p{int(threads)};
    const double ms = median_ms([&](int rep) {
      place(t, d, rep, at);
      frame.update(tb.maps, at);
      runtime::transfer_gains(tb.maps, frame, a, &p);
    });
    std::printf("  cpu maps,   %u thread%s   %8.3f ms per update\n", threads,
                threads > 1 ? "s" : " ", ms);
    row["cpu_maps_" + std::to_string(threads) + "_threads_ms"] = ms;
  }
  const double series_ms = median_ms([&](int rep) {
    place(t, d, rep, at);
    frame.update(tb.series, at);
    runtime::transfer_gains(tb.series, frame, b, &pool);
  });
  std::printf("  cpu series, %u threads   %8.3f ms per update\n", hw, series_ms);
  row["cpu_series_ms"] = series_ms;
  if (!gpu) return;
  double device = 0;
  const double ms = median_ms([&](int rep) {
    place(t, d, rep, at);
    frame.update(tb.series, at, true);
    gpu->compute(frame, b);
    device = gpu->last_device_ms();
  });
  std::printf("  gpu series (%s)  %8.3f ms per update (device %.3f ms)\n", ctx->info().name.c_str(),
              ms, device);
  row["gpu_series_ms"] = ms;
  row["gpu_device_ms"] = device;
  row["gpu"] = ctx->info().name;
}

// Maps against the series over 31 listener positions at distance d, per mode off its nulls:
// where the series gives at least 10 % (-20 dB) or 1 % (-40 dB) of the mode's largest gain over
// those positions.
void map_accuracy(const Transfer& t, double d, Tables& tb, runtime::ThreadPool& pool,
                  nlohmann::json& row) {
  const std::size_t n = tb.maps.mode_count();
  std::vector<Vec3> at(tb.maps.objects.size());
  runtime::ListenerFrame frame;
  std::vector<float> a(n), b(n);
  std::vector<std::vector<float>> ga, gb;
  for (int rep = 0; rep < 31; ++rep) {
    place(t, d, rep, at);
    frame.update(tb.maps, at);
    runtime::transfer_gains(tb.maps, frame, a, &pool);
    frame.update(tb.series, at);
    runtime::transfer_gains(tb.series, frame, b, &pool);
    ga.emplace_back(a.begin(), a.begin() + t.mode_count());
    gb.emplace_back(b.begin(), b.begin() + t.mode_count());
  }
  for (const double floor : {0.1, 0.01}) {
    std::vector<double> err;
    for (std::size_t i = 0; i < t.mode_count(); ++i) {
      float peak = 0;
      for (const auto& g : gb) peak = std::max(peak, g[i]);
      for (std::size_t r = 0; r < gb.size(); ++r)
        if (gb[r][i] > floor * peak && ga[r][i] > 0)
          err.push_back(std::abs(20 * std::log10(double(ga[r][i]) / gb[r][i])));
    }
    std::sort(err.begin(), err.end());
    const double p99 = err.empty() ? 0 : err[err.size() * 99 / 100];
    const double worst = err.empty() ? 0 : err.back();
    const double median = err.empty() ? 0 : err[err.size() / 2];
    std::printf(
        "  maps against series above %2.0f dB below the peak: median %.3f dB, 99th "
        "percentile %.3f dB, worst %.3f dB\n",
        -20 * std::log10(floor), median, p99, worst);
    const std::string key = floor > 0.05 ? "map_error_20db" : "map_error_40db";
    row[key] = {{"median_db", median}, {"p99_db", p99}, {"max_db", worst}};
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s BANK [--gain-modes M] [--distances d,...] [--json OUT]\n",
                 argv[0]);
    return 2;
  }
  try {
    const Args args = parse_args(argc, argv);
    const Soundbank bank = read_soundbank(args.bank);
    if (!bank.transfer) throw std::runtime_error(args.bank + " has no transfer");
    const Transfer& t = *bank.transfer;
    const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
    runtime::ThreadPool pool{int(hw)};
    nlohmann::json j;
    j["bank"] = args.bank;
    j["modes_per_object"] = t.mode_count();
    j["radius_m"] = t.radius;
    j["threads"] = hw;
    Tables tb;
    build_tables(args, t, pool, hw, tb, j);

    std::shared_ptr<gpu::Context> ctx;
    try {
      ctx = std::make_shared<gpu::Context>();
    } catch (const gpu::NoDeviceError& e) {
      std::printf("no Vulkan device (%s): GPU rows skipped\n", e.what());
    }
    std::unique_ptr<runtime::GpuTransferGains> gpu;
    if (ctx) gpu = std::make_unique<runtime::GpuTransferGains>(ctx, tb.series);
    for (double d : args.distances) {
      nlohmann::json& row = j["distances"][std::to_string(d)];
      std::printf("listener at %.1f R (%.2f m):\n", d, d * t.radius);
      time_updates(t, d, tb, gpu.get(), ctx.get(), pool, hw, row);
      map_accuracy(t, d, tb, pool, row);
    }
    if (!args.json.empty()) std::ofstream(args.json) << j.dump(2) << '\n';
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
