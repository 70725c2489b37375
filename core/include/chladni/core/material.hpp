#pragma once
// An isotropic linear-elastic material and its damping, and the presets of data/materials.json.
#include <string>
#include <string_view>
#include <vector>

#include "chladni/core/damping.hpp"

namespace chladni {

struct Material {
  std::string name = "custom";
  double youngs_modulus = 0;  ///< E (Pa)
  double poisson_ratio = 0;   ///< nu
  double density = 0;         ///< rho (kg/m^3)
  DampingModel damping;
  std::string source;  ///< where the values come from

  /// Throws InputError unless E > 0, -1 < nu < 0.5, rho > 0 and all are finite.
  void validate() const;
  /// Lame parameters lambda and mu (Pa).
  double lame_lambda() const;
  double lame_mu() const;
  /// Shear wave speed sqrt(mu / rho) (m/s).
  double shear_speed() const;
};

/// The presets shipped in data/materials.json (embedded at build time).
const std::vector<Material>& material_presets();

/// "NAME" or "NAME:VARIANT" (a damping variant such as sl2016-wood:caughey). Throws InputError
/// listing the known names when there is no such preset.
Material find_material(std::string_view name);

/// The user's own presets (saved by `chladni estimate --save-material`): $CHLADNI_MATERIALS, else
/// $XDG_CONFIG_HOME/chladni/materials.json, else ~/.config/chladni/materials.json. The file has
/// the format of data/materials.json; find_material() looks there after the shipped presets.
std::string user_materials_path();

/// The user's presets (empty when the file does not exist). Throws InputError naming the file
/// when it is malformed.
std::vector<Material> user_material_presets();

/// Throws InputError unless `name` can name a user preset: 1 to 64 letters, digits, '-', '_' or
/// '.', and not the name of a shipped preset.
void check_material_name(const std::string& name);

/// Adds `m` to the user's presets (replacing one of the same name), written atomically.
void save_user_material(const Material& m);

/// Parses a materials file in the format of data/materials.json; `origin` names it in errors.
std::vector<Material> parse_materials(std::string_view json_text, const std::string& origin);

}  // namespace chladni
