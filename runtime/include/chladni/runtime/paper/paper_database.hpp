#pragma once
// The paper-sound databases (Schreck et al. 2016 §5): crumpling clips (time domain) and
// friction magnitude spectra, indexed by resonator size (l_r, l_c), plus the (0, 0) entry for
// constrained resonators. On disk a database is a folder of recordings (WAV, FLAC, anything
// libsndfile reads) and a paper_db.json index (docs/paper.md, "Sound databases"), so users can
// replace the generated default with their own recordings. Generating and writing one is offline
// work: tools/paper_db_generate.hpp.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "chladni/runtime/paper/paper_sheet.hpp"
#include "chladni/runtime/paper/spectral_noise.hpp"

namespace chladni::runtime {

struct PaperDbEntry {
  bool constrained = false;                 ///< the (0, 0) entry
  double l_r = 0, l_c = 0;                  ///< m
  std::vector<std::vector<float>> crumple;  ///< clips at the database's sample rate
  /// Surface name ("wood", ...) -> magnitude spectra of kFrictionBins bins (friction_spectrum).
  std::map<std::string, std::vector<std::vector<float>>> friction;
};

struct PaperSoundDb {
  double sample_rate = 44100;
  /// The sliding speed (m/s) at which the friction recordings were made: playback scales
  /// linearly with speed / this (the paper: 20 cm in 2 s).
  double friction_reference_speed = 0.1;
  std::string description;
  std::vector<PaperDbEntry> entries;

  /// The entry nearest (l_r, l_c) in the grid's (l_r, l_c) plane, or the constrained entry.
  /// Entries without crumple clips (or without `surface`'s spectra) are skipped for that use.
  const PaperDbEntry& nearest_crumple(double l_r, double l_c, bool constrained) const;
  const PaperDbEntry& nearest_friction(const std::string& surface, double l_r, double l_c,
                                       bool constrained) const;
  bool has_surface(const std::string& surface) const;
  std::vector<std::string> surfaces() const;
  /// Throws InputError naming the entry when something is missing or not finite.
  void validate() const;
};

/// The paper's grid of l_r and l_c values: 2.5, 5, 7.5, 10, 12.5, 15, 20, 25, 30 cm.
std::vector<double> paper_db_grid();

/// Reads DIR/paper_db.json and the recordings it names; errors name the file and JSON path.
PaperSoundDb load_paper_database(const std::string& dir);

}  // namespace chladni::runtime
