#pragma once
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <string>

#include "chladni/core/error.hpp"
#include "chladni/core/vec3.hpp"

namespace chladni::cli {

namespace detail {
// A finite number in [lo, hi], or in (lo, hi] when open_low (CLI::Range lets NaN and infinities
// of the wrong sign through).
inline CLI::Validator finite_range(double lo, double hi, bool open_low) {
  const std::string range =
      (open_low ? "(" : "[") + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, open_low, range](std::string& text) -> std::string {
        double v = 0;
        std::size_t used = 0;
        try {
          v = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used != text.size() || text.empty()) return "not a number: '" + text + "'";
        if (!std::isfinite(v) || v < lo || (open_low && v == lo) || v > hi)
          return "must be a finite number in " + range + ", not " + text;
        return {};
      },
      "NUMBER in " + range);
}
}  // namespace detail

/// Every numeric option is bounded where it is declared, so its help shows the limits
/// (docs/robustness.md lists them): a finite number in [lo, hi] ...
inline CLI::Validator finite_in(double lo, double hi) {
  return detail::finite_range(lo, hi, false);
}
/// ... or in (lo, hi].
inline CLI::Validator finite_above(double lo, double hi) {
  return detail::finite_range(lo, hi, true);
}

/// Worker threads: 0 (all cores) up to 1024.
inline CLI::Validator thread_count() {
  return CLI::Range(0, 1024);
}

/// An "X,Y,Z" option in metres (`what` names it): three finite numbers, nothing after them.
inline Vec3 parse_vec3(const std::string& s, const char* what) {
  Vec3 v{};
  char tail = 0;
  if (std::sscanf(s.c_str(), "%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &tail) != 3 || !is_finite(v))
    throw InputError(std::string(what) + " must be X,Y,Z in metres, got '" + s + "'");
  return v;
}

/// Thrown by a command that ends with a non-zero exit code it has already explained.
struct ExitCode {
  int code;
};

// Each adds its subcommand to `app`; the callback runs it (errors propagate as exceptions).
void add_render(CLI::App& app);
void add_play(CLI::App& app);
void add_bench(CLI::App& app);
void add_devices(CLI::App& app);
/// `run` false: parse and check the options only (the batch checks its manifests so).
void add_precompute(CLI::App& app, bool run = true);
void add_materials(CLI::App& app);
void add_info(CLI::App& app);
void add_report(CLI::App& app);
void add_radiate(CLI::App& app);
void add_paper(CLI::App& app);
void add_shake(CLI::App& app);
void add_batch(CLI::App& app);
void add_estimate(CLI::App& app);

}  // namespace chladni::cli
