#pragma once
// The soundbank (.chbank): what precompute produces and the runtime loads. A versioned
// little-endian binary with a section table and a CRC-32 per section (docs/soundbank-format.md).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "chladni/core/material.hpp"
#include "chladni/core/modal_model.hpp"
#include "chladni/core/transfer.hpp"

namespace chladni {

struct Soundbank {
  static constexpr uint16_t kVersionMajor = 1;
  /// 1.1: XFER holds a Transfer; 1.2: XFER's per-mode reserved word holds method and iterations;
  /// 1.3: method 2, the time-domain wave solve
  static constexpr uint16_t kVersionMinor = 3;

  std::string metadata_json = "{}";  ///< META: free-form JSON (source mesh, settings, timings)
  Material material;                 ///< MATL: elastic constants and damping model
  std::vector<double> omega;         ///< MODE: undamped angular frequency (rad/s), ascending
  std::vector<double> decay;         ///< MODE: decay rate d = c / 2 (1/s)
  std::vector<float> residual;       ///< MODE: ||K v - lambda M v|| / ||K v|| of the eigen-solve
  std::vector<Vec3> vertices;        ///< SURF: surface vertices (m)
  std::vector<std::array<uint32_t, 3>> triangles;  ///< SURF: counter-clockwise seen from outside
  std::vector<std::array<float, 3>> normals;       ///< SURF: outward unit vertex normals
  /// SHAP: mass-normalized mode shapes at the surface vertices, [mode][vertex][xyz].
  std::vector<float> shapes;
  std::optional<Transfer> transfer;  ///< XFER: acoustic transfer per mode (optional)

  std::size_t mode_count() const { return omega.size(); }
  /// Damped angular frequency omega_d = sqrt(omega^2 - d^2) (0 when overdamped).
  double damped_omega(std::size_t mode) const {
    return damped_angular_frequency(omega[mode], decay[mode]);
  }
  /// Throws InputError naming the first inconsistent count, bad index or non-finite value.
  void validate() const;
};

/// Writes atomically (to a temporary file, then renamed). Throws InputError on I/O failure.
void write_soundbank(const std::string& path, const Soundbank& bank);
/// Reads and validates every section; a truncated or corrupted file raises InputError naming
/// the file and the section.
Soundbank read_soundbank(const std::string& path);
/// The same from bytes in memory; `origin` names them in messages.
Soundbank parse_soundbank(const std::vector<uint8_t>& bytes, const std::string& origin);
std::vector<uint8_t> serialize_soundbank(const Soundbank& bank);

/// The runtime's view of a bank: modes, surface points, normals, shapes and transfer. Each mode's
/// radiation gain (used without transfer) is the compact-source estimate
/// rho0 / (4 pi) * sqrt(|Q|^2 + k^2 |D|^2 / 3) from its surface monopole Q and dipole D moments.
ModalModel to_modal_model(const Soundbank& bank, const std::string& name);

}  // namespace chladni
