#include <algorithm>
#include <cmath>
#include <optional>

#include "chladni/core/error.hpp"
#include "chladni/precompute/eigensolve.hpp"

namespace chladni::precompute {

// Meshing for a high frequency can take minutes before the memory check after it refuses.
// Coarser meshes first give a lower bound on that check's figure: from the coarsest quality mesh,
// bounds 5 times smaller each time down to 27 times `max_volume` (edges 3 times as long),
// stopping once a sample has kSampleTets tetrahedra, so the samples take seconds.
double check_memory_for_surface(const SurfaceMesh& surface, double solid, double max_volume,
                                int order, const TetOptions& tet, const EigenOptions& eo) {
  constexpr std::size_t kSampleTets = 50000;
  // Refused at once for its size by tetrahedralize, or close to the coarsest mesh: quick.
  const double coarsest = coarse_max_volume(surface);
  if (eo.max_memory <= 0 || !(max_volume > 0) || solid / max_volume > double(kMaxTetrahedra) ||
      coarsest < 27 * max_volume)
    return 0;
  std::optional<TetMesh> prev, last;
  double prev_bound = 0, last_bound = 0;
  for (double b = coarsest;; b /= 5) {
    TetOptions t = tet;
    t.max_volume = std::max(b, 27 * max_volume);
    try {
      TetMesh m = tetrahedralize(surface, t);
      prev = std::move(last), prev_bound = last_bound;
      last = std::move(m), last_bound = t.max_volume;
    } catch (const InputError&) {
      // TetGen fails on some surfaces at some bounds only (rotor.obj at its coarsest): skip it.
    }
    if ((last && last->tets.size() >= kSampleTets) || t.max_volume <= 27 * max_volume) break;
  }
  if (!prev) return 0;  // fewer than two samples: meshing itself will say why it fails
  // Tetrahedra within a bound: the interior's count grows as 1/bound, the surface's slower, so
  // the growth between the samples, extrapolated, undercounts; and every one is within it.
  const double t1 = double(prev->tets.size()), t2 = double(last->tets.size());
  const double growth = std::clamp(std::log(t2 / t1) / std::log(prev_bound / last_bound), 0.0, 1.0);
  const double tets = std::max(solid / max_volume, t2 * std::pow(last_bound / max_volume, growth));
  return check_memory_extrapolated(make_fem_mesh(*prev, order), make_fem_mesh(*last, order), tets,
                                   eo);
}

}  // namespace chladni::precompute
