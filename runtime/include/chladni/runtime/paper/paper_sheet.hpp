#pragma once
// The vibrating paper sheet behind the default sound database and the modal resonator voices
// (docs/paper.md): the modes of a bent rectangular sheet l_r x l_c/2, modelled as a simply
// supported shallow cylindrical panel, and the micro-impulse bursts of a crumple.
#include <cstdint>
#include <vector>

#include "chladni/core/random.hpp"

namespace chladni::runtime {

/// Office paper, 80 g/m^2 and 0.1 mm thick; E, nu and damping: docs/paper.md.
struct PaperMaterial {
  double thickness = 1e-4;         ///< m
  double surface_density = 0.080;  ///< kg/m^2
  double young = 4e9;              ///< Pa, between machine- and cross-direction moduli
  double poisson = 0.3;
  double loss_factor = 0.04;  ///< structural: decay = loss_factor * omega / 2 + air_decay
  double air_decay = 30;      ///< 1/s, air loading and friction at the supports
  /// The database sheets are bent so their curved edges' chord is this fraction of their
  /// length (the paper's recordings: compressed by 30%); sets the panel radius.
  double chord_ratio = 0.7;
};

struct SheetMode {
  double omega = 0;            ///< rad/s, damped
  double decay = 0;            ///< 1/s
  std::uint16_t m = 1, n = 1;  ///< half-waves along the ruling (l_r) and across it (l_c/2)
  float weight = 1;            ///< > 1 when the mode stands for several dropped neighbours
};

/// Shallow-panel radius (m) of a curved edge of length b bent to the material's chord ratio.
double sheet_radius(double b, const PaperMaterial& material);

/// Modes of the simply supported shallow cylindrical panel of length a along its straight
/// generator (ruling) and arc length b, radius R (R <= 0: flat plate), sorted by frequency,
/// between min_hz and max_hz. Donnell-type shallow-shell frequency (Soedel, "Vibrations of
/// Shells and Plates", 3rd ed. 2004, §5; Leissa, NASA SP-288, 1973, ch. 5):
///   omega^2 = D/(rho h) (kx^2 + ky^2)^2 + E/(rho R^2) kx^4 / (kx^2 + ky^2)^2,
///   kx = m pi / a, ky = n pi / b, D = E h^3 / (12 (1 - nu^2)).
std::vector<SheetMode> sheet_modes(double a, double b, double R, const PaperMaterial& material,
                                   double min_hz, double max_hz);

/// Keeps at most `count` modes spread evenly in log frequency; each kept mode's weight becomes
/// sqrt(modes it stands for), so the summed energy of noise-driven modes is preserved.
std::vector<SheetMode> thin_modes(const std::vector<SheetMode>& modes, std::size_t count);

/// Mode (m, n)'s shape at a point (u, v) in [0,1]^2 of the sheet: sin(m pi u) sin(n pi v).
double sheet_mode_shape(const SheetMode& mode, double u, double v);

/// One micro-impulse of a crumple: time (s from the burst's start), signed strength, point.
struct CrumpleImpulse {
  double time = 0;
  double strength = 0;
  double u = 0.5, v = 0.5;
};

/// Strength of a click at full system energy (the snap adds 2 to the first).
constexpr double kClickScale = 3.0;

/// A crumple burst (Houle and Sethna 1996: crumpling emits a train of discrete clicks that dies
/// away): one shake of the PhISEM "paper" instrument, clicks at its collision rate with
/// strengths kClickScale times the decaying system energy, random signs, uniform points; the
/// first click is the snap. Deterministic in the generator.
std::vector<CrumpleImpulse> crumple_burst(Rng& rng);

}  // namespace chladni::runtime
