// What makes a soundbank current: a hash of the tool version, the mesh and the options, recorded
// in the bank's META by the precompute that made it.
#include <xxhash.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "chladni/core/input_file.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/core/version.hpp"
#include "chladni/precompute/batch.hpp"

namespace chladni::precompute::batch {

std::string input_stamp(const Asset& a) {
  XXH3_state_t* state = XXH3_createState();
  XXH3_128bits_reset(state);
  // Each part is preceded by its length, so no two different inputs concatenate alike.
  const auto add = [&](const void* data, std::size_t n) {
    const std::uint64_t len = n;
    XXH3_128bits_update(state, &len, sizeof len);
    XXH3_128bits_update(state, data, n);
  };
  const std::string version = std::string("chladni ") + kVersion;
  add(version.data(), version.size());
  try {
    const std::vector<std::uint8_t> mesh = read_input_file(a.mesh, "mesh", kMaxBinaryInputBytes);
    add(mesh.data(), mesh.size());
  } catch (const std::exception&) {
    XXH3_freeState(state);
    return {};  // the precompute will say what is wrong with the mesh
  }
  for (const std::string& arg : a.args) add(arg.data(), arg.size());
  const XXH128_hash_t h = XXH3_128bits_digest(state);
  XXH3_freeState(state);
  char hex[33];
  std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                static_cast<unsigned long long>(h.low64));
  return hex;
}

std::string recorded_stamp(const std::string& path) {
  try {
    const Soundbank bank = read_soundbank(path);  // checks every section's CRC
    const nlohmann::json meta = nlohmann::json::parse(bank.metadata_json);
    if (meta.is_object() && meta.contains("batch_stamp") && meta["batch_stamp"].is_string())
      return meta["batch_stamp"].get<std::string>();
  } catch (const std::exception&) {
  }
  return {};
}

}  // namespace chladni::precompute::batch
