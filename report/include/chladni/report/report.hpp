#pragma once
// A soundbank as a self-contained HTML report (index.html and its scripts, no network): the mode
// table, a WebGL view of the surface coloured and moved by each mode, each mode's directivity
// from its multipoles, and click-to-strike audio synthesized in the browser with the runtime's
// impact formula (docs/report.md).
#include <optional>
#include <string>

#include "chladni/core/soundbank.hpp"
#include "chladni/core/vec3.hpp"

namespace chladni::report {

struct ReportOptions {
  std::string bank_path;         ///< shown in the title and summary
  std::string mesh_path;         ///< optional display mesh, in the bank's frame and unit
  double mesh_scale = 1.0;       ///< metres per unit of the display mesh
  std::optional<Vec3> listener;  ///< m, object frame; default: 4 R (at least 1 m) diagonally
  std::size_t max_modes = 400;   ///< the lowest modes shown and struck
  double sample_rate = 48000;    ///< of the strike synthesized in the browser
  double impulse = 0.01;         ///< N s, of a click
  double contact_time = 2e-4;    ///< s, half-sine contact of a click
  int directivity_angles = 72;   ///< per plane
  /// The mode shapes the page carries (3 floats per mode and surface point) stay under this:
  /// past it, fewer modes are shown.
  double max_shape_bytes = 128e6;
};

struct ReportSummary {
  std::size_t modes_shown = 0, bank_modes = 0;
  bool limited_by_size = false;  ///< max_shape_bytes, not max_modes, set modes_shown
  std::size_t bytes = 0;         ///< of the data file
};

/// What the report holds, as the JSON object assigned to window.CHLADNI_REPORT in bank-data.js.
std::string report_json(const Soundbank& bank, const ReportOptions& options,
                        ReportSummary* summary = nullptr);

/// Writes index.html, report.css, viewer.js, strike.js, report.js and bank-data.js into `dir`
/// (created if missing; each file replaced atomically). InputError naming the path when it
/// cannot; nothing is written when the bank or mesh is refused.
ReportSummary write_report(const std::string& dir, const Soundbank& bank,
                           const ReportOptions& options);

}  // namespace chladni::report
