// chladni report BANK -o DIR: the soundbank as a self-contained HTML page (docs/report.md).
#include <cstdio>
#include <memory>

#include "chladni/core/error.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/report/report.hpp"
#include "commands.hpp"

namespace chladni::cli {
namespace {

struct ReportArgs {
  std::string bank, output, mesh, unit = "m", listener;
  report::ReportOptions options;
};

void run_report(ReportArgs& a) {
  report::ReportOptions& o = a.options;
  o.bank_path = a.bank;
  o.mesh_path = a.mesh;
  o.mesh_scale = precompute::unit_scale(a.unit);
  if (!a.listener.empty()) o.listener = parse_vec3(a.listener, "--listener");
  const Soundbank bank = read_soundbank(a.bank);
  const report::ReportSummary r = report::write_report(a.output, bank, o);
  std::printf(
      "wrote %s/index.html: %zu of %zu modes, %.1f MB of data (open it in a browser; "
      "no network needed)\n",
      a.output.c_str(), r.modes_shown, r.bank_modes, r.bytes / 1e6);
  if (r.limited_by_size)
    std::fprintf(stderr,
                 "report: only the lowest %zu modes: their shapes on %zu surface points fill the "
                 "%.0f MB the page may carry (--max-modes to choose fewer)\n",
                 r.modes_shown, bank.vertices.size(), o.max_shape_bytes / 1e6);
}

}  // namespace

void add_report(CLI::App& app) {
  auto a = std::make_shared<ReportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "report", "Write a soundbank as an HTML report: modes, 3-D mode shapes, click-to-strike");
  cmd->add_option("bank", a->bank, "Soundbank (.chbank)")->required();
  cmd->add_option("-o,--output", a->output, "Output folder (index.html and its files)")->required();
  cmd->add_option("--mesh", a->mesh,
                  "Show this mesh instead of the bank's surface (same frame; see --unit)");
  cmd->add_option("--unit", a->unit, "Length unit of --mesh: m, cm, mm")->capture_default_str();
  cmd->add_option("--listener", a->listener,
                  "Listener X,Y,Z (m, object frame); default 4 R (at least 1 m) diagonally");
  cmd->add_option("--max-modes", a->options.max_modes, "Show and strike at most this many modes")
      ->check(CLI::Range(1, 5000))
      ->capture_default_str();
  cmd->add_option("--impulse", a->options.impulse, "Impulse of a click (N s)")
      ->check(finite_in(1e-9, 1e3))
      ->capture_default_str();
  cmd->add_option("--contact-time", a->options.contact_time,
                  "Half-sine contact of a click (s; 0: ideal impulse)")
      ->check(finite_in(0, 0.05))
      ->capture_default_str();
  cmd->add_option("--sample-rate", a->options.sample_rate, "Of the strike's audio (Hz)")
      ->check(CLI::Range(8000.0, 192000.0))
      ->capture_default_str();
  cmd->callback([a] { run_report(*a); });
}

}  // namespace chladni::cli
