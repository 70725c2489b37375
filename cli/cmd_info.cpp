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
#include "chladni/report/bank_facts.hpp"
#include "commands.hpp"
#include "info_plot.hpp"

namespace chladni::cli {
namespace {

struct InfoArgs {
  std::string bank, plot;
  bool json = false;
};

void print_transfer(const Transfer& t) {
  std::printf(
      "transfer  multipole about (%.4g, %.4g, %.4g) m, R %.4g m, c %.4g m/s, rho0 %.4g "
      "kg/m^3; %zu coefficients; %zu poor fits (held-out error > %.0f%%)\n",
      t.centre[0], t.centre[1], t.centre[2], t.radius, t.sound_speed, t.air_density,
      t.coefficients.size(), t.poor_fits(), 100.0 * Transfer::kPoorFit);
  std::size_t bem = 0, wave = 0;
  for (const ModeTransfer& m : t.modes) {
    bem += m.method == TransferMethod::Bem;
    wave += m.method == TransferMethod::Wave;
  }
  if (bem > 0)
    std::printf(
        "          %zu modes by BEM (Burton-Miller): src/el. = boundary elements, residual = "
        "linear solve, held-out = interior null-field error\n",
        bem);
  if (wave > 0)
    std::printf(
        "          %zu modes by the time-domain wave solve: iters = chord, src/el. = grid cells, "
        "residual = chord separation, held-out = the mode's separation error\n",
        wave);
}

// What --repair did (META "repair"), one line; a field missing from an older bank reads as 0.
void print_repair(const nlohmann::json& r) {
  auto num = [&](const nlohmann::json& j, const char* k) {
    return j.contains(k) && j[k].is_number() ? j[k].get<double>() : 0.0;
  };
  const std::string rung =
      r.contains("rung") && r["rung"].is_string() ? r["rung"].get<std::string>() : "?";
  std::printf("repair    %s", rung.c_str());
  if (r.contains("wrap") && r["wrap"].is_object())
    std::printf(" (alpha %.3g mm, offset %.3g mm)", 1e3 * num(r["wrap"], "alpha_m"),
                1e3 * num(r["wrap"], "offset_m"));
  if (rung != "none") {
    const double size = num(r, "size_m");
    std::printf(
        ": surface moved up to %.3g mm (%.2f %% of its size; input to repaired %.3g mm, "
        "repaired to input %.3g mm), volume %+.2f %%",
        1e3 * num(r, "hausdorff_m"), size > 0 ? 100 * num(r, "hausdorff_m") / size : 0.0,
        1e3 * num(r, "input_to_repaired_m"), 1e3 * num(r, "repaired_to_input_m"),
        100 * num(r, "volume_change"));
  }
  std::printf("\n");
}

void print_summary(const std::string& path, const Soundbank& b, const nlohmann::json& meta,
                   bool have_ferr) {
  std::printf("soundbank %s (format %u.%u)\n", path.c_str(), Soundbank::kVersionMajor,
              Soundbank::kVersionMinor);
  std::printf("material  %s: E %.4g Pa, nu %.3g, rho %.4g kg/m^3\n", b.material.name.c_str(),
              b.material.youngs_modulus, b.material.poisson_ratio, b.material.density);
  std::printf("damping   %s\n", b.material.damping.to_string().c_str());
  if (!b.material.source.empty()) std::printf("source    %s\n", b.material.source.c_str());
  std::printf("surface   %zu vertices, %zu triangles\n", b.vertices.size(), b.triangles.size());
  if (b.transfer)
    print_transfer(*b.transfer);
  else
    std::printf("transfer  none (listener gains use a compact-source estimate)\n");
  if (meta.is_object() && meta.contains("repair") && meta["repair"].is_object())
    print_repair(meta["repair"]);
  if (meta.is_object())
    for (const auto& [k, v] : meta.items())
      if ((k != "frequency_error_estimate" || !have_ferr) && k != "repair")
        std::printf("meta      %s: %s\n", k.c_str(), v.dump().c_str());
  if (have_ferr)
    std::printf(
        "          f. err = estimated relative frequency error of the elements (precompute "
        "--tolerance)\n");
}

void print_mode_table(const Soundbank& b, const std::vector<double>& ferr) {
  std::printf("%zu modes\n%6s %12s %12s %12s %10s %10s", b.mode_count(), "mode", "freq (Hz)",
              "decay (1/s)", "damp. ratio", "T60 (s)", "residual");
  if (!ferr.empty()) std::printf(" %8s", "f. err");
  if (b.transfer)
    std::printf(" %7s %5s %5s %7s %9s %9s %9s", "method", "iters", "order", "src/el.", "residual",
                "held-out", "expansion");
  std::printf("\n");
  for (std::size_t i = 0; i < b.mode_count(); ++i) {
    const report::ModeFacts r = report::mode_facts(b, i);
    std::printf("%6zu %12.2f %12.4g %12.3g %10.3g %10.2g", i, r.frequency_hz, r.decay_per_s,
                r.damping_ratio, r.t60_s, r.residual);
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

void run_info(const InfoArgs& a) {
  if (!a.plot.empty()) check_output_path(a.plot, "--plot");
  const Soundbank b = read_soundbank(a.bank);
  if (!a.plot.empty()) {
    write_info_plot(a.plot, a.bank, b);
    if (!a.json) std::printf("wrote %s\n", a.plot.c_str());
  }
  if (a.json) {
    std::printf("%s\n", report::bank_json(a.bank, b).dump(2).c_str());
    return;
  }
  const nlohmann::json meta = report::bank_metadata(b);
  const std::vector<double> ferr = report::frequency_errors(meta, b);
  print_summary(a.bank, b, meta, !ferr.empty());
  print_mode_table(b, ferr);
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
