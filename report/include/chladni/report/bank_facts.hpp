#pragma once
// What a soundbank says about itself, under one set of names for `chladni info`'s table and
// --json and for the report's page: per mode its frequency, decay, damping ratio, T60, residual,
// the precompute's frequency error estimate and the fit of its transfer.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "chladni/core/soundbank.hpp"

namespace chladni::report {

/// Mode i as the bank stores it. t60_s is infinite for an undamped mode.
struct ModeFacts {
  double frequency_hz = 0;   ///< damped, omega_d / 2 pi
  double omega_d = 0;        ///< rad/s
  double decay_per_s = 0;    ///< d = c / 2
  double damping_ratio = 0;  ///< d / omega
  double t60_s = 0;          ///< ln(1000) / d
  double residual = 0;       ///< of the eigen-solve
};
ModeFacts mode_facts(const Soundbank& bank, std::size_t i);

/// The bank's metadata as JSON, or as a JSON string when it does not parse.
nlohmann::json bank_metadata(const Soundbank& bank);

/// The precompute's per-mode frequency error estimates (NaN where it recorded none); empty when
/// the metadata holds none for this bank's modes.
std::vector<double> frequency_errors(const nlohmann::json& metadata, const Soundbank& bank);

nlohmann::json material_json(const Material& material);

/// Mode i: its facts, "frequency_error_estimate" when `errors` is not empty (null where NaN),
/// and "transfer" (method, fit, "poor_fit", "used_at_runtime") when the bank has transfer.
nlohmann::json mode_json(const Soundbank& bank, std::size_t i, const std::vector<double>& errors);

/// The whole bank, as `chladni info --json` prints it: file, format version, metadata,
/// material, surface, transfer and modes.
nlohmann::json bank_json(const std::string& path, const Soundbank& bank);

}  // namespace chladni::report
