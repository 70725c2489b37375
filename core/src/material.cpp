#include "chladni/core/material.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "chladni/core/error.hpp"
#include "materials_data.hpp"

namespace chladni {

void Material::validate() const {
  const std::string who = "material '" + name + "': ";
  if (!std::isfinite(youngs_modulus) || !(youngs_modulus > 0))
    throw InputError(who + "Young's modulus E must be finite and > 0");
  if (!std::isfinite(poisson_ratio) || !(poisson_ratio > -1.0 && poisson_ratio < 0.5))
    throw InputError(who + "Poisson's ratio nu must lie in (-1, 0.5)");
  if (!std::isfinite(density) || !(density > 0))
    throw InputError(who + "density rho must be finite and > 0");
  damping.validate();
}

double Material::lame_lambda() const {
  const double E = youngs_modulus, nu = poisson_ratio;
  return E * nu / ((1 + nu) * (1 - 2 * nu));
}
double Material::lame_mu() const {
  return youngs_modulus / (2 * (1 + poisson_ratio));
}
double Material::shear_speed() const {
  return std::sqrt(lame_mu() / density);
}

std::vector<Material> parse_materials(std::string_view text, const std::string& origin) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(origin + ": " + e.what());
  }
  std::vector<Material> out;
  if (!j.contains("materials") || !j["materials"].is_array())
    throw InputError(origin + ": expected a 'materials' array");
  for (std::size_t i = 0; i < j["materials"].size(); ++i) {
    const auto& e = j["materials"][i];
    const std::string where = origin + ": materials[" + std::to_string(i) + "]";
    try {
      Material base;
      base.name = e.at("name").get<std::string>();
      base.youngs_modulus = e.at("E").get<double>();
      base.poisson_ratio = e.at("nu").get<double>();
      base.density = e.at("rho").get<double>();
      base.damping = DampingModel::parse(e.at("damping").get<std::string>());
      base.source = e.value("source", "");
      base.validate();
      out.push_back(base);
      if (e.contains("variants")) {
        for (const auto& [variant, model] : e["variants"].items()) {
          Material m = base;
          m.name = base.name + ":" + variant;
          m.damping = DampingModel::parse(model.get<std::string>());
          out.push_back(m);
        }
      }
    } catch (const nlohmann::json::exception& ex) {
      throw InputError(where + ": " + ex.what());
    } catch (const InputError& ex) {
      throw InputError(where + ": " + ex.what());
    }
  }
  return out;
}

const std::vector<Material>& material_presets() {
  static const std::vector<Material> presets =
      parse_materials(detail::kMaterialsJson, "data/materials.json");
  return presets;
}

Material find_material(std::string_view name) {
  for (const Material& m : material_presets())
    if (m.name == name) return m;
  std::string known;
  for (const Material& m : material_presets()) known += (known.empty() ? "" : ", ") + m.name;
  throw InputError("unknown material '" + std::string(name) + "'; known: " + known);
}

}  // namespace chladni
