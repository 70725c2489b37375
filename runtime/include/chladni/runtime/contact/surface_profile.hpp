#pragma once
// The roughness a continuous contact traverses: a band-limited fractal height profile along the
// path, spatial power spectrum P(k) = C k^-beta for wavenumbers k (cycles/m) between 1/longest and
// 1/shortest, normalized to unit variance (van den Doel, Kry & Pai, "FoleyAutomatic", SIGGRAPH
// 2001: a 1/f^beta surface read at the contact speed, kept as a looped table). Besides the height,
// the table holds the curvature of the profile as a rolling contact sees it: smoothed by its
// contact patch, H(k) = exp(-(pi k a)^2 / 2) for a patch of diameter a (FoleyAutomatic's rolling
// model; Conan et al., Computer Music Journal 38:4, 2014, where rolling is the surface seen
// through the contact area). A ribbed texture may be added to the profile (Roughness::ribs):
// read at speed v, it sounds at v / spacing and its harmonics.
//
// Read at speed v, a wavenumber k sounds at v k Hz. Each table is kept at levels that halve its
// band, and a read blends the two levels that keep every component below Nyquist (a texture's
// mipmap, in one dimension), so a fast slide never aliases.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace chladni::runtime {

struct Roughness {
  std::string name;
  /// Sliding: rms of the force's fluctuation per newton of normal force.
  double level = 0.1;
  /// Rolling: rms height of the profile (m).
  double height = 2e-6;
  double beta = 2;         ///< spectral exponent of the height profile
  double shortest = 2e-4;  ///< shortest wavelength on the surface (m)
  double longest = 2e-2;   ///< longest (m)
  double patch = 1e-3;     ///< rolling contact patch diameter (m)
  /// A ribbed texture across the path (grooves, a corrugated or knurled surface; Ren, Yeh & Lin,
  /// IEEE VR 2010, meso-level bumps, here in one dimension): the spacing (m; 0: none), rounded
  /// so that whole ribs fill the table's loop...
  double ribs = 0;
  /// ...and its rms beside the fractal's unit rms. Its profile is a triangle wave's harmonics
  /// (amplitude 1 / h^2) up to the table's band.
  double rib_depth = 0;
};

/// Surfaces by material: steel, aluminium, glass, ceramic, wood, stone, plastic.
const std::vector<Roughness>& roughness_presets();
/// Throws InputError naming the known surfaces.
const Roughness& roughness_preset(std::string_view name);
/// Throws InputError naming the first field out of range.
void validate_roughness(const Roughness& r);

class SurfaceProfile {
 public:
  /// Builds the tables (allocates about 2 MB; a control thread). `seed` draws the phases.
  explicit SurfaceProfile(const Roughness& roughness, uint64_t seed = 1);

  /// The unit-rms profile at position `s` (m, any value: the table loops) with only the
  /// wavenumbers that a speed of `speed` m/s keeps below `nyquist` Hz. Allocates nothing.
  float height(double s, double speed, double nyquist) const {
    return read(height_, s, speed, nyquist);
  }
  /// Likewise, d^2/ds^2 of the patch-smoothed unit-rms profile (1/m^2).
  float curvature(double s, double speed, double nyquist) const {
    return read(curvature_, s, speed, nyquist);
  }

  /// One-sided power spectral density of the unit-rms height per cycle/m at wavenumber k.
  double psd(double k) const;
  /// The patch's smoothing at wavenumber k.
  double patch_response(double k) const;
  /// The ribs' wavenumber (1 / their spacing as the loop holds it; 0 without ribs) and the
  /// amplitude of their h-th harmonic in the unit-rms profile's units.
  double rib_wavenumber() const { return rib_k_; }
  double rib_amplitude(int h) const { return rib_k_ > 0 ? rib_a_ / (double(h) * h) : 0.0; }
  double length() const { return length_; }  ///< the loop (m)
  const Roughness& roughness() const { return r_; }

 private:
  Roughness r_;
  std::size_t n_ = 0;  // samples per level
  double dx_ = 0, length_ = 0, k_top_ = 0, c_ = 0;
  double rib_k_ = 0, rib_a_ = 0;
  int levels_ = 0;
  std::vector<float> height_, curvature_;  // level-major, n_ + 1 each (the first repeated)
  float read(const std::vector<float>& table, double s, double speed, double nyquist) const;
};

}  // namespace chladni::runtime
