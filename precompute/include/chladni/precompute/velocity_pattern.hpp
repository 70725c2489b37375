#pragma once
// Normal-velocity patterns with known radiation, to drive a surface for checks against the
// exact field (chladni radiate --pattern, the transfer benchmarks): a uniform (breathing)
// velocity, or a spherical harmonic about the surface's area-weighted centroid.
#include <complex>
#include <vector>

#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

/// Per vertex: U P_l^|m|(cos theta) cos(m phi) for m >= 0, sin(|m| phi) for m < 0, without the
/// Condon-Shortley phase, with theta and phi about the area-weighted centroid. InputError unless
/// 0 <= l <= 40 and |m| <= l.
std::vector<std::complex<double>> harmonic_velocity(const SurfaceMesh& mesh, int l, int m,
                                                    double amplitude);

/// Per vertex: `amplitude` everywhere.
std::vector<std::complex<double>> uniform_velocity(const SurfaceMesh& mesh, double amplitude);

}  // namespace chladni::precompute
