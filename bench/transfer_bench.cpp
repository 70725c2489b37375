// Acoustic-transfer speed (docs/PERFORMANCE.md, "Acoustic transfer"): the fit of the first N modes
// of a soundbank per stage on the CPU (double) and GPU (float) kernels. Listener gains:
// gains_bench.cpp.
// Usage: chladni_transfer_bench BANK [--modes N] [--solver normal|qr]
//        [--method sources|bem|auto] [--hmatrix-limit N] [--bem-solvers 0|1|2]
//        [--backends cpu,gpu] [--json OUT]
// (--method bem or auto: the modes given BEM are solved once per backend, with progress.)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>

#include <sys/resource.h>

#include "bench_support.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/precompute/memory_budget.hpp"

using namespace chladni;
using bench::clock_type;
using bench::seconds_since;

namespace {

struct Args {
  std::string bank, json, solver = "normal", backends = "cpu,gpu", method = "sources";
  std::size_t modes = 100;
  long hmatrix_limit = -1, solvers = 0;
};

Args parse_args(int argc, char** argv) {
  Args a;
  a.bank = argv[1];
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--modes"))
      a.modes = std::stoul(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--json"))
      a.json = argv[i + 1];
    else if (!std::strcmp(argv[i], "--solver"))
      a.solver = argv[i + 1];
    else if (!std::strcmp(argv[i], "--hmatrix-limit"))
      a.hmatrix_limit = std::stol(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--bem-solvers"))
      a.solvers = std::stol(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--method"))
      a.method = argv[i + 1];
    else if (!std::strcmp(argv[i], "--backends"))
      a.backends = argv[i + 1];
  }
  if (a.method != "sources" && a.method != "bem" && a.method != "auto")
    throw std::invalid_argument("--method must be sources, bem or auto");
  return a;
}

precompute::AcousticOptions acoustic_options(const Args& a) {
  precompute::AcousticOptions o;
  o.solver = a.solver == "normal" ? precompute::AcousticOptions::Solver::Normal
                                  : precompute::AcousticOptions::Solver::Qr;
  using M = precompute::AcousticOptions::Method;
  o.method = a.method == "bem" ? M::Bem : a.method == "auto" ? M::Auto : M::Sources;
  o.bem_max_memory = precompute::default_memory_budget();
  if (a.hmatrix_limit >= 0) o.bem.hmatrix_limit = std::size_t(a.hmatrix_limit);
  o.bem_solvers = int(a.solvers);
  return o;
}

// The bank cut to its first `modes`, without its transfer (the fit makes it again).
Soundbank first_modes(Soundbank bank, std::size_t modes) {
  modes = std::min(modes, bank.mode_count());
  const std::size_t nv = bank.vertices.size();
  bank.omega.resize(modes), bank.decay.resize(modes), bank.residual.resize(modes);
  bank.shapes.resize(modes * nv * 3);
  bank.transfer.reset();
  return bank;
}

struct Run {
  const char* name;
  bool gpu;
  int mode_threads;  // 1: modes one after another, each fit using every thread
};

// One fit of every mode on `run`'s kernels: its stage times, printed and as JSON.
nlohmann::json fit_row(const Run& run, const precompute::RadiatingSurface& surf,
                       const Soundbank& bank, const precompute::AcousticOptions& o,
                       const std::shared_ptr<gpu::Context>& ctx, const Args& a) {
  auto kernels = run.gpu ? precompute::make_gpu_transfer_kernels(ctx)
                         : precompute::make_cpu_transfer_kernels(run.mode_threads == 1 ? 0 : 1);
  precompute::AcousticOptions ro = o;
  ro.threads = run.mode_threads;
  precompute::TransferTimes times;
  const auto t0 = clock_type::now();
  Transfer t = precompute::compute_transfer(
      surf, bank, ro, *kernels, &times, [&](std::size_t done, std::size_t total) {
        if (a.method != "sources")
          std::fprintf(stderr, "  %zu/%zu modes, %.0f s\n", done, total, seconds_since(t0));
      });
  const double wall = seconds_since(t0);
  std::size_t poor = 0, coeffs = t.coefficients.size(), bem = 0;
  double sources = 0;
  for (std::size_t i = 0; i < t.mode_count(); ++i) {
    poor += t.poor(i), sources += t.modes[i].sources;
    bem += t.modes[i].method == TransferMethod::Bem;
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const std::string key =
      std::string(run.name) + (run.mode_threads == 1 ? "_sequential" : "_parallel");
  std::printf(
      "fit %-16s %-28s wall %6.2f s | matrices %6.2f  solve %6.2f  expansion %5.2f "
      "(%s) | mean sources or elements %.0f, %zu coefficients, %zu poor fits, %zu by BEM, "
      "peak %.1f GB\n",
      key.c_str(), kernels->name().c_str(), wall, times.matrix, times.solve, times.expand,
      run.mode_threads == 1 ? "s" : "thread-s", sources / double(t.mode_count()), coeffs, poor, bem,
      double(usage.ru_maxrss) / 1e6);
  return {{"key", key},
          {"kernels", kernels->name()},
          {"wall_s", wall},
          {"matrix_s", times.matrix},
          {"solve_s", times.solve},
          {"expand_s", times.expand},
          {"poor_fits", poor},
          {"bem_modes", bem},
          {"peak_rss_gb", double(usage.ru_maxrss) / 1e6},
          {"mean_sources", sources / double(t.mode_count())},
          {"coefficients", coeffs}};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s BANK [--modes N] [--json OUT]\n", argv[0]);
    return 2;
  }
  const Args args = bench::parse_or_exit(parse_args, argc, argv);
  try {
    const Soundbank bank = first_modes(read_soundbank(args.bank), args.modes);
    nlohmann::json j;
    j["bank"] = args.bank;
    j["triangles"] = bank.triangles.size();
    j["modes"] = bank.mode_count();
    j["top_frequency_hz"] = bank.omega.back() / (2 * 3.141592653589793);
    j["threads"] = std::thread::hardware_concurrency();
    j["solver"] = args.solver;
    j["method"] = args.method;
    const precompute::AcousticOptions o = acoustic_options(args);
    const auto t0 = clock_type::now();
    const precompute::RadiatingSurface surf({bank.vertices, bank.triangles}, o);
    j["prepare_s"] = seconds_since(t0);
    j["radius_m"] = surf.radius();
    std::printf(
        "%s: %zu triangles, first %zu modes (to %.0f Hz), R %.3f m; surface preparation %.2f s\n",
        args.bank.c_str(), bank.triangles.size(), bank.mode_count(),
        j["top_frequency_hz"].get<double>(), surf.radius(), j["prepare_s"].get<double>());
    std::shared_ptr<gpu::Context> ctx;
    try {
      ctx = std::make_shared<gpu::Context>();
    } catch (const gpu::NoDeviceError& e) {
      std::printf("no Vulkan device (%s): GPU rows skipped\n", e.what());
    }
    for (const Run run :
         {Run{"cpu", false, 0}, Run{"cpu", false, 1}, Run{"gpu", true, 0}, Run{"gpu", true, 1}}) {
      if (run.gpu && !ctx) continue;
      if (args.backends.find(run.name) == std::string::npos) continue;
      if (args.method == "bem" && run.mode_threads == 1) continue;  // BEM has its own threads
      nlohmann::json row = fit_row(run, surf, bank, o, ctx, args);
      const std::string key = row["key"];
      row.erase("key");
      j["fit"][key] = row;
    }
    if (!args.json.empty()) std::ofstream(args.json) << j.dump(2) << '\n';
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
