#include "chladni/core/material.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "chladni/core/error.hpp"
#include "chladni/core/input_file.hpp"
#include "chladni/core/output_file.hpp"
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

std::string user_materials_path() {
  if (const char* p = std::getenv("CHLADNI_MATERIALS"); p && *p) return p;
  if (const char* x = std::getenv("XDG_CONFIG_HOME"); x && *x)
    return std::string(x) + "/chladni/materials.json";
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : ".") + "/.config/chladni/materials.json";
}

namespace {

// The user's file as JSON (an empty list when it does not exist yet).
nlohmann::json user_materials_json(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    return {
        {"format", "chladni-materials"}, {"version", 1}, {"materials", nlohmann::json::array()}};
  const auto bytes = read_input_file(path, "materials file", kMaxTextInputBytes);
  const std::string text(bytes.begin(), bytes.end());
  parse_materials(text, path);  // the whole file must be valid
  return nlohmann::json::parse(text);
}

}  // namespace

std::vector<Material> user_material_presets() {
  const std::string path = user_materials_path();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return {};
  const auto bytes = read_input_file(path, "materials file", kMaxTextInputBytes);
  return parse_materials(std::string(bytes.begin(), bytes.end()), path);
}

void check_material_name(const std::string& name) {
  const bool ok =
      !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
      });
  if (!ok)
    throw InputError("material name '" + name + "': use 1 to 64 letters, digits, '-', '_' or '.'");
  for (const Material& m : material_presets())
    if (m.name == name)
      throw InputError("material name '" + name + "' is a shipped preset; choose another");
}

void save_user_material(const Material& m) {
  check_material_name(m.name);
  m.validate();
  const std::string path = user_materials_path();
  nlohmann::json j = user_materials_json(path);
  nlohmann::json entry = {{"name", m.name},
                          {"E", m.youngs_modulus},
                          {"nu", m.poisson_ratio},
                          {"rho", m.density},
                          {"damping", m.damping.to_string()},
                          {"source", m.source}};
  auto& list = j["materials"];
  bool replaced = false;
  for (auto& e : list)
    if (e.value("name", "") == m.name) e = entry, replaced = true;
  if (!replaced) list.push_back(entry);
  std::error_code ec;
  const auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("cannot create " + dir.string() + ": " + ec.message());
  write_file_atomic(path, j.dump(2) + "\n", "materials file");
}

Material find_material(std::string_view name) {
  for (const Material& m : material_presets())
    if (m.name == name) return m;
  const std::vector<Material> own = user_material_presets();
  for (const Material& m : own)
    if (m.name == name) return m;
  std::string known;
  for (const Material& m : material_presets()) known += (known.empty() ? "" : ", ") + m.name;
  for (const Material& m : own) known += ", " + m.name + " (" + user_materials_path() + ")";
  throw InputError("unknown material '" + std::string(name) + "'; known: " + known);
}

}  // namespace chladni
