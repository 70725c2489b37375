#pragma once
// Time-domain acoustic transfer with mode conflation (after Wang & James 2019, "KleinPAT: optimal
// mode conflation for time-domain precomputation of acoustic transfer"). The linear acoustic
// equations in pressure p and scaled velocity w = rho0 c v,
//   dw/dt = -c grad p,   dp/dt = -c div w,
// are stepped on a staggered (Yee) grid around the object, with Berenger's split-field perfectly
// matched layer outside. Faces of the grid crossed by the surface carry the surface's velocity
// along their axis, summed over the modes of a "chord": modes far enough apart in frequency to be
// told apart in a short recording. After the start-up transient, p and w on a box around the
// object are separated per mode by least squares against the chord's sinusoids, and each mode's
// far field follows from the Kirchhoff-Helmholtz integral over that box as multipoles
// (core/transfer.hpp), like the boundary-element path's. docs/transfer.md has the rules.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "chladni/core/vec3.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::gpu {
class Context;
}

namespace chladni::precompute {

struct WaveOptions {
  /// Grid cells per wavelength at a chord's highest frequency (the grid halves its error per
  /// doubling of this; docs/transfer.md measures it).
  double cells_per_wavelength = 8.0;
  /// At least this many cells along the object's longest side, whatever the frequency.
  int min_cells = 32;
  int pml_cells = 10;    ///< perfectly matched layer on every side
  int margin_cells = 3;  ///< air between the object's box and the recording box
  double courant = 0.5;  ///< c dt / h (stable below 1/sqrt 3)
  /// Fit window = this / (smallest gap in the chord): the chord's sinusoids stay independent.
  double beats = 1.5;
  double ramp_periods = 3.0;  ///< smooth start over this many periods of the chord's lowest mode
  /// Modes share a grid (a band) within this ratio of frequencies; the band's highest sets h.
  double band_ratio = 1.5;
  std::size_t max_chord = 48;  ///< modes per chord
  /// Modes of a shared chord whose separation error (relative to their own amplitude) exceeds
  /// this are stepped again among themselves: a mode that barely radiates, beside loud ones,
  /// drowns in their residue. The better separation is kept. 0: no second pass.
  double retry_separation = 0.1;
  /// Orientations of the object against the grid, turned 90 / grid_turns degrees apart about
  /// its axis of near symmetry; the expansions are averaged. Each costs a run. Two cancel the
  /// staircase's coupling through the grid's four-fold symmetry (a bowl's cos 3 phi and cos 4
  /// phi modes leaking onto its axis).
  int grid_turns = 2;
  /// Bytes a grid may take (0: no limit); a mode whose grid exceeds it is not solved this way.
  double max_memory = 0;
  /// Most cells x steps one chord may take (2e11: about 4 minutes of the CPU stepper on two
  /// cores); beyond it a mode is not solved this way, so an odd scale cannot run for hours.
  double max_cell_steps = 2e11;
  /// Vulkan device for the stepping kernels (kernels/wave_*.comp, float); null: the CPU loops.
  std::shared_ptr<gpu::Context> gpu;
  int threads = 0;  ///< CPU stepping threads (0: all cores)
  void validate() const;
};

/// Modes stepped together: indices into the caller's list, ascending in frequency.
struct Chord {
  std::vector<std::size_t> modes;
  double f_min = 0, f_max = 0;  ///< Hz
  double min_gap = 0;           ///< smallest frequency gap inside the chord (Hz; 0: one mode)
};

/// Bands of frequency ratio band_ratio from the top down; in each, modes packed first-fit into
/// chords whose members lie at least a gap apart, the gap chosen to minimise simulated time
/// (chords x (settling + beats / gap)). Near-degenerate modes land in different chords.
std::vector<Chord> plan_chords(std::span<const double> hz, double settle_seconds,
                               const WaveOptions& options);

/// The grid a chord needs for an object of bounding box [lo, hi] (m).
struct WaveGridSize {
  double h = 0;  ///< cell size (m)
  std::size_t nx = 0, ny = 0, nz = 0;
  double dt = 0;          ///< s
  std::size_t steps = 0;  ///< settle + fit window
  std::size_t settle_steps = 0;
  std::size_t stride = 1;  ///< steps between recorded samples
  std::size_t turns = 1;   ///< runs, one per orientation
  double bytes = 0;        ///< estimated peak memory of the solve
  std::size_t cells() const { return nx * ny * nz; }
  double cell_steps() const { return double(cells()) * double(steps) * double(turns); }
};

/// How an object sits on its grids: the orientations it is stepped in and the box that holds it
/// in all of them.
struct WaveLayout {
  /// Object to grid, x_grid = pivot + rows (x - pivot), one per orientation: the object turned
  /// 90 / turns degrees apart about `axis`.
  std::vector<std::array<Vec3, 3>> turns;
  int axis = 2;             ///< the coordinate axis nearest the surface's axis of near symmetry
  double fourfold = 0;      ///< the surface's cos 4 phi content about it (0: a body of revolution)
  Vec3 pivot{0, 0, 0};      ///< the object's bounding-box centre
  double lo[3]{}, hi[3]{};  ///< bounding box over all orientations (m)
};
/// options.grid_turns orientations where the surface is nearly of revolution about a coordinate
/// axis (fourfold <= 0.05, and its two other principal moments within 5 %), else one: turning a
/// body that has a four-fold shape of its own (a square bar) changes its staircase, not only the
/// grid's, and a body of no symmetry gains too little for twice the work. Throws InputError on
/// an empty mesh.
WaveLayout wave_layout(const SurfaceMesh& mesh, const WaveOptions& options);

/// The grid a chord needs (one per orientation).
WaveGridSize wave_grid_size(const WaveLayout& layout, const Chord& chord, double sound_speed,
                            double surface_area, const WaveOptions& options);

}  // namespace chladni::precompute
