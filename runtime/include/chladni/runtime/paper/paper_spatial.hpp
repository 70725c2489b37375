#pragma once
// Spatialization of paper resonators (Schreck et al. 2016 §6): each resonator radiates as a
// small vibrating disk, a dipole p = a^3 cos(theta) / R * A(t - R/c) (Eq. 3), and each nearby
// rigid plane (table, wall) adds an image dipole at the mirrored position with the mirrored
// normal: a delayed, weighted copy in time for crumpling (Eq. 5) and a complex factor on
// friction spectra (Eq. 6).
#include <complex>
#include <span>
#include <vector>

#include "chladni/core/paper_animation.hpp"
#include "chladni/core/vec3.hpp"

namespace chladni::runtime {

/// One sound path from a source to an ear: gain a^3 cos(theta) / R (relative, see
/// PaperSpatialOptions::reference_radius) and propagation delay R / c.
struct SoundPath {
  double gain = 0;
  double delay = 0;  ///< s
};

struct PaperSpatialOptions {
  double sound_speed = 343;
  /// Planes farther than this from the source (m) add no image: their reflection arrives
  /// late and weak enough to belong to room acoustics, not to the paper's near-field colour.
  double max_image_distance = 1.0;
  /// Sources closer to an ear than this (m) are treated as this far (keeps 1/R finite).
  double min_distance = 0.05;
};

/// The ears' positions: listener position -/+ (ear_distance / 2) along forward x up (left,
/// right).
std::array<Vec3, 2> ear_positions(const PaperListener& listener);

/// Direct and first-order image paths from a disk of radius `a` at `center` with unit normal
/// `normal` to point `ear`, through the planes in `obstacles` (Eq. 3-5). The gain is relative:
/// (a / reference_radius)^3 cos(theta) / R with R in metres, so a disk of the reference radius
/// facing the ear 1 m away has gain 1. An image's gain is weighted by min(1, h / a) for a
/// source at height h (docs/paper.md: a sheet lying on a table must not cancel). Appends.
void dipole_paths(const Vec3& center, const Vec3& normal, double a, double reference_radius,
                  const Vec3& ear, std::span<const PaperObstacle> obstacles,
                  const PaperSpatialOptions& options, std::vector<SoundPath>& out);

/// Eq. 6: the magnitude |sum_p gain_p e^{i omega delay_p}| at angular frequency omega.
double path_magnitude(std::span<const SoundPath> paths, double omega);

}  // namespace chladni::runtime
