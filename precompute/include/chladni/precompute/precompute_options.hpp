#pragma once
// What the pipeline takes (PrecomputeOptions), what it reports (PrecomputeReport) and the hooks it
// reports progress through: the types its stages share, apart from the functions that run them
// (chladni/precompute.hpp).
#include <functional>
#include <string>

#include "chladni/core/soundbank.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/precompute/eigensolve.hpp"
#include "chladni/precompute/fem.hpp"
#include "chladni/precompute/mesh_repair.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/precompute/tet_mesh.hpp"

namespace chladni::precompute {

struct PrecomputeOptions {
  double scale = 1.0;  ///< coordinates times scale = metres (unit and --scale combined)
  bool repair = false;
  /// When set, the checked (repaired, simplified) surface, the one meshed, is written here as OBJ.
  std::string save_surface;
  RepairOptions repair_options;
  Material material = find_material("steel");
  int order = 2;  ///< quadratic tets by default: linear ones lock in bending (docs/validation.md)
  MassKind mass = MassKind::Consistent;
  std::size_t max_modes = 0;  ///< the first N below max_frequency; 0: every mode below it
  double max_frequency = 20000;
  double min_frequency = 20;
  double sample_rate = 48000;  ///< damped frequencies above sample_rate / 2 are dropped
  /// m^3; 0: chosen by the solver: the first mesh is sized from max_frequency (auto_max_volume)
  /// or, with max_modes, is the coarsest quality mesh (coarse_max_volume), and it is refined
  /// where the error estimate asks until the modes asked for are within `tolerance`.
  double max_tet_volume = 0;
  /// A surface of more triangles is simplified toward half as many before it is meshed, within
  /// an envelope that moves no frequency by more than a fifth of `tolerance`
  /// (simplify_surface.hpp); 0: never. Not with max_tet_volume, which fixes the elements.
  std::size_t max_surface_triangles = 20000;
  /// Target relative frequency error of every mode asked for, by the a-posteriori estimate
  /// (mode_error.hpp).
  double tolerance = 0.01;
  int max_passes = 4;  ///< meshes solved at most while refining
  /// Refine where the estimate puts the error (TetGen refining the last mesh), or else the whole
  /// mesh under one smaller bound (also the fallback when local refinement fails).
  bool local_refinement = true;
  TetOptions tet;
  int threads = 0;
  std::size_t mode_cap = 2000;
  EigenOptions::Method eigensolver = EigenOptions::Method::BlockLanczos;
  /// Bytes the eigen-solve's factor, matrices and basis may take (EigenOptions::max_memory);
  /// 0: no limit;
  /// negative: default_memory_budget().
  double max_memory = -1;
  bool transfer = true;  ///< fit acoustic transfer per mode (XFER)
  AcousticOptions acoustic;
  /// Recorded in META as "batch_stamp": the batch's hash of what made this soundbank.
  std::string batch_stamp;
  /// Vulkan device for the transfer kernels; null: the double-precision CPU kernels.
  std::shared_ptr<gpu::Context> gpu;
};

/// Throws InputError, naming the option as the command line spells it, for options the pipeline
/// cannot run with (a material out of range, an order other than 1 or 2, a band, sample rate,
/// element bound or tolerance that is not finite or out of range).
void validate(const PrecomputeOptions& options);

struct StageTime {
  std::string name;
  double seconds = 0;
  /// The largest resident memory (bytes) of the process, or of a child it waited for (TetGen's,
  /// the second BEM solver's), while the stage ran; over a stage repeated on refined meshes, the
  /// largest. 0 where the kernel cannot say (docs/PERFORMANCE.md, "Memory per stage").
  double peak_bytes = 0;
};

struct PrecomputeReport {
  MeshReport mesh;
  RepairReport repair;  ///< with PrecomputeOptions::repair: the rung used and how far it moved
  /// Triangles of the checked surface before it was simplified (0: it was not), and the
  /// envelope (m) the simplified one stays within.
  std::size_t simplified_from = 0;
  double simplify_envelope = 0;
  double max_tet_volume = 0;
  /// Per kept mode: the estimated relative frequency error (f_h - f) / f of the final mesh.
  std::vector<double> frequency_error;
  /// Each mesh solved, coarse to fine: its size and the largest estimate over the modes asked for.
  struct MeshPass {
    std::size_t tets = 0, dofs = 0;
    double worst_error = 0;
    double seconds = 0;
    double max_tet_volume = 0;  ///< its bound (refined locally: its finest region's)
    /// With all modes below max_frequency: the modes its memory check sized the Lanczos basis
    /// for (the first mesh: the estimate made before meshing; a refined one: what the previous
    /// mesh found, raised by its error). 0 when the modes were asked for by count.
    std::size_t expected_modes = 0;
  };
  std::vector<MeshPass> passes;
  bool converged = true;           ///< every mode asked for is within PrecomputeOptions::tolerance
  std::string unconverged_reason;  ///< why refining stopped short, when it did
  std::size_t tets = 0, nodes = 0, dofs = 0, nonzeros = 0;
  TetQuality quality;
  EigenResult eigen;  ///< vectors are released after use
  std::size_t computed = 0, overdamped = 0, below_band = 0, above_band = 0, kept = 0;
  double max_residual = 0;
  std::string transfer_kernels;  ///< which kernels ran ("" without transfer)
  TransferTimes transfer_times;  ///< summed over the threads that fitted modes
  std::size_t poor_fits = 0;
  double max_held_out = 0;
  std::vector<StageTime> stages;
  double total_seconds = 0;
  double peak_bytes = 0;  ///< the largest of the stages' peaks (0: unknown)
};

/// Hooks for a progress display: a stage starts (name), a fraction of it is done, a note.
struct Progress {
  std::function<void(const std::string&)> stage;
  std::function<void(double)> fraction;
  std::function<void(const std::string&)> note;
};

}  // namespace chladni::precompute
