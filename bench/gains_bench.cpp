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

#include "chladni/core/soundbank.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/runtime/modal/transfer_gains.hpp"
#include "chladni/runtime/thread_pool.hpp"

using namespace chladni;
using clock_type = std::chrono::steady_clock;

namespace {

double since(clock_type::time_point t0) {
  return std::chrono::duration<double>(clock_type::now() - t0).count();
}

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
    ms.push_back(1e3 * since(s));
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s BANK [--gain-modes M] [--distances d,...] [--json OUT]\n",
                 argv[0]);
    return 2;
  }
  std::string bank_path = argv[1], json_path, distances_arg = "3,10,30";
  std::size_t gain_modes = 100000;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--gain-modes"))
      gain_modes = std::stoul(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--distances"))
      distances_arg = argv[i + 1];
    else if (!std::strcmp(argv[i], "--json"))
      json_path = argv[i + 1];
  }
  std::vector<double> distances;
  std::stringstream ds(distances_arg);
  for (std::string tok; std::getline(ds, tok, ',');) distances.push_back(std::stod(tok));
  try {
    const Soundbank bank = read_soundbank(bank_path);
    if (!bank.transfer) throw std::runtime_error(bank_path + " has no transfer");
    const Transfer& t = *bank.transfer;
    const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
    runtime::ThreadPool pool{int(hw)};
    nlohmann::json j;
    j["bank"] = bank_path;
    j["modes_per_object"] = t.mode_count();
    j["radius_m"] = t.radius;
    j["threads"] = hw;

    runtime::TransferTable maps, series;
    series.map_options.reset();
    auto t0 = clock_type::now();
    maps.add(t, &pool);
    const double build_s = since(t0);
    series.add(t);
    while (maps.mode_count() < gain_modes) maps.add_instance(0), series.add_instance(0);
    const runtime::GainMap& m = maps.maps[0];
    std::vector<float> valid = m.valid_radius;
    std::sort(valid.begin(), valid.end());
    const double median_valid = valid[valid.size() / 2] / t.radius;
    std::string grids;
    for (const auto& g : m.grids)
      grids += " " + std::to_string(g.rows) + "x" + std::to_string(g.cols) + ":" +
               std::to_string(g.modes.size());
    std::printf(
        "%s: %zu modes per object, R %.3f m; %zu modes in %zu objects, %.0f coefficients per mode\n"
        "maps: %.1f MB, built in %.2f s (%u threads); grids (rows x cols: modes)%s\n"
        "  valid radius: median %.1f R, largest %.1f R; %u of %u modes series-only\n",
        bank_path.c_str(), t.mode_count(), t.radius, maps.mode_count(), maps.objects.size(),
        double(t.coefficients.size()) / double(t.mode_count()), m.bytes() / 1e6, build_s, hw,
        grids.c_str(), median_valid, m.max_valid_radius / t.radius, m.series_modes, m.modes);
    j["modes"] = maps.mode_count();
    j["objects"] = maps.objects.size();
    j["coefficients_per_mode"] = double(t.coefficients.size()) / double(t.mode_count());
    j["map"] = {{"grids", grids},
                {"megabytes", m.bytes() / 1e6},
                {"build_s", build_s},
                {"series_only_modes", m.series_modes},
                {"median_valid_radius_R", median_valid},
                {"max_valid_radius_R", m.max_valid_radius / t.radius}};

    std::shared_ptr<gpu::Context> ctx;
    try {
      ctx = std::make_shared<gpu::Context>();
    } catch (const gpu::NoDeviceError& e) {
      std::printf("no Vulkan device (%s): GPU rows skipped\n", e.what());
    }
    std::unique_ptr<runtime::GpuTransferGains> gpu;
    if (ctx) gpu = std::make_unique<runtime::GpuTransferGains>(ctx, series);

    const std::size_t n = maps.mode_count();
    std::vector<Vec3> at(maps.objects.size());
    runtime::ListenerFrame frame;
    std::vector<float> a(n), b(n);
    for (double d : distances) {
      auto place = [&](int rep) {
        for (std::size_t o = 0; o < at.size(); ++o) at[o] = listener_at(t, d, rep, o);
      };
      nlohmann::json& row = j["distances"][std::to_string(d)];
      std::printf("listener at %.1f R (%.2f m):\n", d, d * t.radius);
      for (unsigned threads : {1u, hw}) {
        runtime::ThreadPool p{int(threads)};
        const double ms = median_ms([&](int rep) {
          place(rep);
          frame.update(maps, at);
          runtime::transfer_gains(maps, frame, a, &p);
        });
        std::printf("  cpu maps,   %u thread%s   %8.3f ms per update\n", threads,
                    threads > 1 ? "s" : " ", ms);
        row["cpu_maps_" + std::to_string(threads) + "_threads_ms"] = ms;
      }
      const double series_ms = median_ms([&](int rep) {
        place(rep);
        frame.update(series, at);
        runtime::transfer_gains(series, frame, b, &pool);
      });
      std::printf("  cpu series, %u threads   %8.3f ms per update\n", hw, series_ms);
      row["cpu_series_ms"] = series_ms;
      if (gpu) {
        double device = 0;
        const double ms = median_ms([&](int rep) {
          place(rep);
          frame.update(series, at, true);
          gpu->compute(frame, b);
          device = gpu->last_device_ms();
        });
        std::printf("  gpu series (%s)  %8.3f ms per update (device %.3f ms)\n",
                    ctx->info().name.c_str(), ms, device);
        row["gpu_series_ms"] = ms;
        row["gpu_device_ms"] = device;
        row["gpu"] = ctx->info().name;
      }
      // Accuracy: maps against the series over 31 listener positions, per mode off its nulls
      // (gains above 1 % of the mode's largest gain over those positions).
      std::vector<std::vector<float>> ga, gb;
      for (int rep = 0; rep < 31; ++rep) {
        place(rep);
        frame.update(maps, at);
        runtime::transfer_gains(maps, frame, a, &pool);
        frame.update(series, at);
        runtime::transfer_gains(series, frame, b, &pool);
        ga.emplace_back(a.begin(), a.begin() + t.mode_count());
        gb.emplace_back(b.begin(), b.begin() + t.mode_count());
      }
      // Off the nulls: where the series gives at least 10 % (-20 dB) or 1 % (-40 dB) of the
      // mode's largest gain over these positions.
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
    if (!json_path.empty()) std::ofstream(json_path) << j.dump(2) << '\n';
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
