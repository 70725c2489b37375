#pragma once
// The default paper sound database, generated from the bent-sheet model and written as a folder
// (runtime/paper_database.hpp reads it): offline work the runtime does not need.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "chladni/runtime/paper/paper_database.hpp"

namespace chladni::tools {

using runtime::PaperMaterial;
using runtime::PaperSoundDb;

struct PaperDbOptions {
  std::uint64_t seed = 1;
  int variants = 3;  ///< per entry; variant v bends the sheet to chord ratio 0.65, 0.7, 0.75, ...
  PaperMaterial material;
  double clip_seconds = 0.25;
  std::vector<std::string> surfaces = {"wood"};
  std::size_t clip_modes = 256;       ///< modes kept for clip synthesis (thin_modes)
  std::size_t spectrum_modes = 1024;  ///< modes kept for the friction spectra
  /// The (0, 0) entry: a square patch of this side held at its border (ridges, fingers).
  double constrained_side = 0.03;
};

/// The default database from the sheet model: for each grid entry and variant, the modes of a
/// bent l_r x l_c/2 sheet; clips are their response to crumple_burst(); friction spectra are
/// the expected spectrum of their response to white-noise forcing at random points.
/// Deterministic in options.seed. `progress` (may be empty) gets the fraction done.
PaperSoundDb generate_paper_database(const PaperDbOptions& options,
                                     const std::function<void(double)>& progress = {});

/// Writes DIR/paper_db.json, DIR/crumple/*.wav and DIR/friction/*.wav (the spectra as noise
/// recordings of `friction_seconds`, made by SpectralNoise). Creates DIR.
void write_paper_database(const std::string& dir, const PaperSoundDb& db,
                          double friction_seconds = 1.0, std::uint64_t seed = 1);

}  // namespace chladni::tools
