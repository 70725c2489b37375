#pragma once
#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

namespace chladni::cli {

/// A number that must be finite and lie in [lo, hi] (CLI::Range lets NaN and infinities of the
/// wrong sign through).
inline CLI::Validator finite_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        double v = 0;
        std::size_t used = 0;
        try {
          v = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used != text.size() || text.empty()) return "not a number: '" + text + "'";
        if (!std::isfinite(v) || v < lo || v > hi)
          return "must be a finite number in [" + CLI::detail::to_string(lo) + ", " +
                 CLI::detail::to_string(hi) + "], not " + text;
        return {};
      },
      "NUMBER in [" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]");
}

/// Worker threads: 0 (all cores) up to 1024.
inline CLI::Validator thread_count() {
  return CLI::Range(0, 1024);
}

// Each adds its subcommand to `app`; the callback runs it (errors propagate as exceptions).
void add_render(CLI::App& app);
void add_bench(CLI::App& app);
void add_devices(CLI::App& app);
void add_precompute(CLI::App& app);
void add_materials(CLI::App& app);
void add_info(CLI::App& app);
void add_radiate(CLI::App& app);
void add_paper(CLI::App& app);
void add_shake(CLI::App& app);

}  // namespace chladni::cli
