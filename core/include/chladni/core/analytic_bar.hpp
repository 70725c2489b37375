#pragma once
// Analytic modes of a free-free rectangular bar: Euler-Bernoulli bending across the thickness
// (z) and across the width (y), and axial modes along x. Scenes play them without a precompute
// ("bar" objects), and they are a validation reference for the FEM pipeline
// (meshes/README.md lists the values for bar.obj). Needs only core, so a runtime-only
// build plays bars.
#include "chladni/core/modal_model.hpp"
#include "chladni/core/scene.hpp"

namespace chladni {

/// Mass-normalized modes with undamped frequency below bar.max_frequency, sorted by frequency,
/// with a compact-dipole estimate of each mode's radiation (see analytic_bar.cpp),
/// with shapes sampled at `points_per_edge` stations along the bar's top centre line
/// (x in [0, L], y = W/2, z = H), normals +z. Damping is not applied (decay = 0).
ModalModel analytic_bar(const BarSpec& bar, int points_per_edge = 61);

/// beta_n L for free-free bending mode n (n = 1, 2, ...): roots of cos(x) cosh(x) = 1.
double free_free_beta_l(int n);

}  // namespace chladni
