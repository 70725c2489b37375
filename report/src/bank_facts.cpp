#include "chladni/report/bank_facts.hpp"

#include <cmath>
#include <numbers>

namespace chladni::report {

using nlohmann::json;

ModeFacts mode_facts(const Soundbank& b, std::size_t i) {
  const double w = b.omega[i], d = b.decay[i], wd = b.damped_omega(i);
  return {wd / (2 * std::numbers::pi),
          wd,
          d,
          d / w,
          d > 0 ? std::log(1000.0) / d : INFINITY,
          b.residual[i]};
}

json bank_metadata(const Soundbank& b) {
  json meta = json::parse(b.metadata_json, nullptr, false);
  return meta.is_discarded() ? json(b.metadata_json) : meta;
}

std::vector<double> frequency_errors(const json& meta, const Soundbank& b) {
  std::vector<double> ferr;
  if (meta.is_object() && meta.contains("frequency_error_estimate") &&
      meta["frequency_error_estimate"].is_array() &&
      meta["frequency_error_estimate"].size() == b.mode_count())
    for (const auto& e : meta["frequency_error_estimate"])
      ferr.push_back(e.is_number() ? e.get<double>() : NAN);
  return ferr;
}

json material_json(const Material& m) {
  return {{"name", m.name},
          {"E", m.youngs_modulus},
          {"nu", m.poisson_ratio},
          {"rho", m.density},
          {"damping", m.damping.to_string()},
          {"source", m.source}};
}

namespace {

json finite_or_null(double x) {
  return std::isfinite(x) ? json(x) : json(nullptr);
}

json transfer_json(const Transfer& t) {
  return {{"centre", t.centre},
          {"radius_m", t.radius},
          {"sound_speed", t.sound_speed},
          {"air_density", t.air_density},
          {"coefficients", t.coefficients.size()},
          {"poor_fit_threshold", Transfer::kPoorFit},
          {"poor_fits", t.poor_fits()}};
}

}  // namespace

json mode_json(const Soundbank& b, std::size_t i, const std::vector<double>& ferr) {
  const ModeFacts f = mode_facts(b, i);
  json m = {{"frequency_hz", f.frequency_hz},   {"omega_d", f.omega_d},
            {"decay_per_s", f.decay_per_s},     {"damping_ratio", f.damping_ratio},
            {"t60_s", finite_or_null(f.t60_s)}, {"residual", f.residual}};
  if (!ferr.empty()) m["frequency_error_estimate"] = finite_or_null(ferr[i]);
  if (b.transfer) {
    const ModeTransfer& t = b.transfer->modes[i];
    m["transfer"] = {{"method", to_string(t.method)},
                     {"iterations", t.iterations},
                     {"order", t.order},
                     {"sources", t.sources},
                     {"fit_residual", t.fit_residual},
                     {"held_out_error", t.held_out_error},
                     {"expansion_error", t.expansion_error},
                     {"poor_fit", b.transfer->poor(i)},
                     {"used_at_runtime", b.transfer->usable(i)}};
  }
  return m;
}

json bank_json(const std::string& path, const Soundbank& b) {
  const json meta = bank_metadata(b);
  const std::vector<double> ferr = frequency_errors(meta, b);
  json j;
  j["file"] = path;
  j["version"] =
      std::to_string(Soundbank::kVersionMajor) + "." + std::to_string(Soundbank::kVersionMinor);
  j["metadata"] = meta;
  j["material"] = material_json(b.material);
  j["surface"] = {{"vertices", b.vertices.size()}, {"triangles", b.triangles.size()}};
  j["transfer"] = b.transfer ? transfer_json(*b.transfer) : json(nullptr);
  j["modes"] = json::array();
  for (std::size_t i = 0; i < b.mode_count(); ++i) j["modes"].push_back(mode_json(b, i, ferr));
  return j;
}

}  // namespace chladni::report
