// chladni info BANK [--json]: a soundbank's metadata and mode table.
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <vector>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/core/soundbank.hpp"
#include "commands.hpp"
#include "info_plot.hpp"

namespace chladni::cli {
namespace {

struct InfoArgs {
  std::string bank, plot;
  bool json = false;
};

void run_info(const InfoArgs& a) {
  if (!a.plot.empty()) check_output_path(a.plot, "--plot");
  const Soundbank b = read_soundbank(a.bank);
  if (!a.plot.empty()) {
    write_info_plot(a.plot, a.bank, b);
    if (!a.json) std::printf("wrote %s\n", a.plot.c_str());
  }
  nlohmann::json meta = nlohmann::json::parse(b.metadata_json, nullptr, false);
  if (meta.is_discarded()) meta = b.metadata_json;
  const double ln1000 = std::log(1000.0);
  // Per-mode frequency error estimates (precompute's a-posteriori estimate), if recorded.
  std::vector<double> ferr;
  if (meta.is_object() && meta.contains("frequency_error_estimate") &&
      meta["frequency_error_estimate"].is_array() &&
      meta["frequency_error_estimate"].size() == b.mode_count())
    for (const auto& e : meta["frequency_error_estimate"])
      ferr.push_back(e.is_number() ? e.get<double>() : NAN);
  auto row = [&](std::size_t i) {
    const double w = b.omega[i], d = b.decay[i];
    const double wd = std::sqrt(w * w - d * d);
    struct {
      double f, d, zeta, t60, res;
    } r{wd / (2 * std::numbers::pi), d, d / w, d > 0 ? ln1000 / d : INFINITY, b.residual[i]};
    return r;
  };
  if (a.json) {
    nlohmann::json j;
    j["file"] = a.bank;
    j["version"] =
        std::to_string(Soundbank::kVersionMajor) + "." + std::to_string(Soundbank::kVersionMinor);
    j["metadata"] = meta;
    j["material"] = {{"name", b.material.name},
                     {"E", b.material.youngs_modulus},
                     {"nu", b.material.poisson_ratio},
                     {"rho", b.material.density},
                     {"damping", b.material.damping.to_string()},
                     {"source", b.material.source}};
    j["surface"] = {{"vertices", b.vertices.size()}, {"triangles", b.triangles.size()}};
    if (b.transfer) {
      const Transfer& t = *b.transfer;
      std::size_t poor = 0;
      for (std::size_t i = 0; i < t.mode_count(); ++i) poor += t.poor(i);
      j["transfer"] = {{"centre", t.centre},
                       {"radius_m", t.radius},
                       {"sound_speed", t.sound_speed},
                       {"air_density", t.air_density},
                       {"coefficients", t.coefficients.size()},
                       {"poor_fit_threshold", Transfer::kPoorFit},
                       {"poor_fits", poor}};
    } else {
      j["transfer"] = nullptr;
    }
    nlohmann::json modes = nlohmann::json::array();
    for (std::size_t i = 0; i < b.mode_count(); ++i) {
      const auto r = row(i);
      modes.push_back(
          {{"frequency_hz", r.f},
           {"decay_per_s", r.d},
           {"damping_ratio", r.zeta},
           {"t60_s", std::isfinite(r.t60) ? nlohmann::json(r.t60) : nlohmann::json(nullptr)},
           {"residual", r.res}});
      if (!ferr.empty())
        modes.back()["frequency_error_estimate"] =
            std::isfinite(ferr[i]) ? nlohmann::json(ferr[i]) : nlohmann::json(nullptr);
      if (b.transfer) {
        const ModeTransfer& m = b.transfer->modes[i];
        modes.back()["transfer"] = {{"method", to_string(m.method)},
                                    {"iterations", m.iterations},
                                    {"order", m.order},
                                    {"sources", m.sources},
                                    {"fit_residual", m.fit_residual},
                                    {"held_out_error", m.held_out_error},
                                    {"expansion_error", m.expansion_error},
                                    {"poor_fit", b.transfer->poor(i)},
                                    {"used_at_runtime", b.transfer->usable(i)}};
      }
    }
    j["modes"] = modes;
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("soundbank %s (format %u.%u)\n", a.bank.c_str(), Soundbank::kVersionMajor,
              Soundbank::kVersionMinor);
  std::printf("material  %s: E %.4g Pa, nu %.3g, rho %.4g kg/m^3\n", b.material.name.c_str(),
              b.material.youngs_modulus, b.material.poisson_ratio, b.material.density);
  std::printf("damping   %s\n", b.material.damping.to_string().c_str());
  if (!b.material.source.empty()) std::printf("source    %s\n", b.material.source.c_str());
  std::printf("surface   %zu vertices, %zu triangles\n", b.vertices.size(), b.triangles.size());
  std::size_t poor = 0;
  if (b.transfer) {
    const Transfer& t = *b.transfer;
    for (std::size_t i = 0; i < t.mode_count(); ++i) poor += t.poor(i);
    std::printf(
        "transfer  multipole about (%.4g, %.4g, %.4g) m, R %.4g m, c %.4g m/s, rho0 %.4g "
        "kg/m^3; %zu coefficients; %zu poor fits (held-out error > %.0f%%)\n",
        t.centre[0], t.centre[1], t.centre[2], t.radius, t.sound_speed, t.air_density,
        t.coefficients.size(), poor, 100.0 * Transfer::kPoorFit);
    std::size_t bem = 0;
    for (const ModeTransfer& m : t.modes) bem += m.method == TransferMethod::Bem;
    if (bem > 0)
      std::printf(
          "          %zu modes by BEM (Burton-Miller): src/el. = boundary elements, residual = "
          "linear solve, held-out = interior null-field error\n",
          bem);
  } else {
    std::printf("transfer  none (listener gains use a compact-source estimate)\n");
  }
  if (meta.is_object())
    for (const auto& [k, v] : meta.items())
      if (k != "frequency_error_estimate" || ferr.empty())
        std::printf("meta      %s: %s\n", k.c_str(), v.dump().c_str());
  if (!ferr.empty())
    std::printf(
        "          f. err = estimated relative frequency error of the elements (precompute "
        "--tolerance)\n");
  std::printf("%zu modes\n%6s %12s %12s %12s %10s %10s", b.mode_count(), "mode", "freq (Hz)",
              "decay (1/s)", "damp. ratio", "T60 (s)", "residual");
  if (!ferr.empty()) std::printf(" %8s", "f. err");
  if (b.transfer)
    std::printf(" %7s %5s %5s %7s %9s %9s %9s", "method", "iters", "order", "src/el.", "residual",
                "held-out", "expansion");
  std::printf("\n");
  for (std::size_t i = 0; i < b.mode_count(); ++i) {
    const auto r = row(i);
    std::printf("%6zu %12.2f %12.4g %12.3g %10.3g %10.2g", i, r.f, r.d, r.zeta, r.t60, r.res);
    if (!ferr.empty()) std::printf(" %7.2f%%", 100 * ferr[i]);
    if (b.transfer) {
      const ModeTransfer& m = b.transfer->modes[i];
      std::printf(" %7s %5u %5u %7u %9.2e %9.2e %9.2e%s", to_string(m.method), m.iterations,
                  m.order, m.sources, m.fit_residual, m.held_out_error, m.expansion_error,
                  !b.transfer->usable(i) ? "  POOR FIT (unused: compact-source gain instead)"
                  : b.transfer->poor(i)  ? "  POOR FIT"
                                         : "");
    }
    std::printf("\n");
  }
}

}  // namespace

void add_info(CLI::App& app) {
  auto a = std::make_shared<InfoArgs>();
  CLI::App* cmd = app.add_subcommand("info", "Print a soundbank's metadata and mode table");
  cmd->add_option("bank", a->bank, "Soundbank (.chbank)")->required();
  cmd->add_flag("--json", a->json, "Print JSON instead of a table");
  cmd->add_option("--plot", a->plot,
                  "Also write a PNG: damping ratio per mode with the material's curve, and each "
                  "mode's radiation at 1 m");
  cmd->callback([a] { run_info(*a); });
}

}  // namespace chladni::cli
