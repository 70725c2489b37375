#include "chladni/precompute/precompute_options.hpp"

#include <cmath>

#include "chladni/core/error.hpp"

namespace chladni::precompute {

void validate(const PrecomputeOptions& o) {
  o.material.validate();
  if (o.order != 1 && o.order != 2) throw InputError("--order must be 1 or 2");
  if (!(o.max_frequency > o.min_frequency) || !(o.min_frequency >= 0) ||
      !std::isfinite(o.max_frequency))
    throw InputError("--max-freq must be finite and above the 20 Hz floor");
  if (!(o.sample_rate >= 8000 && o.sample_rate <= 384000))
    throw InputError("--sample-rate must lie in [8000, 384000] Hz");
  if (!(o.max_tet_volume >= 0) || !std::isfinite(o.max_tet_volume))
    throw InputError("--max-tet-volume must be finite and >= 0");
  if (!(o.tolerance > 0 && o.tolerance < 1)) throw InputError("--tolerance must lie in (0, 1)");
}

}  // namespace chladni::precompute
