#pragma once
// The FEM solve refined until the modes asked for meet the error estimate's tolerance.
#include <algorithm>
#include <chrono>
#include <string>

#include "chladni/precompute/mode_error.hpp"
#include "chladni/precompute/precompute_options.hpp"
#include "peak_memory.hpp"

namespace chladni::precompute {

// Stage times into the report (a stage repeated on a refined mesh adds up) and to the progress.
class Stopwatch {
 public:
  Stopwatch(PrecomputeReport& r, const Progress& p) : r_(r), p_(p) {}
  void start(const std::string& name) {
    stop();
    name_ = name;
    t0_ = std::chrono::steady_clock::now();
    reset_peak_memory();
    if (p_.stage) p_.stage(name);
  }
  void stop() {
    if (name_.empty()) return;
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    auto it = std::find_if(r_.stages.begin(), r_.stages.end(),
                           [&](const StageTime& s) { return s.name == name_; });
    const double peak = peak_memory_bytes();
    if (it == r_.stages.end()) {
      r_.stages.push_back({name_, dt, peak});
    } else {
      it->seconds += dt;  // a stage repeated on a refined mesh
      it->peak_bytes = std::max(it->peak_bytes, peak);
    }
    name_.clear();
  }

 private:
  PrecomputeReport& r_;
  const Progress& p_;
  std::string name_;
  std::chrono::steady_clock::time_point t0_;
};

// One FEM solve on `tets`: assemble, find the modes, estimate their errors.
struct FemPass {
  TetMesh tets;
  TetQuality quality;
  std::size_t nodes = 0, dofs = 0, nonzeros = 0;
  EigenResult eigen;
  ModeErrors errors;
};

/// Meshes the solid, solves, and refines where the estimate asks until the modes asked for are
/// within o.tolerance, o.max_passes meshes or the memory budget allow. `first` receives the first
/// mesh's boundary: the surface the soundbank keeps.
FemPass solve_to_tolerance(const SurfaceMesh& surface, const PrecomputeOptions& o,
                           const EigenOptions& eo, const Progress& p, Stopwatch& sw,
                           PrecomputeReport& r, SurfaceMesh& first);

}  // namespace chladni::precompute
