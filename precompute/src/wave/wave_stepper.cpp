#include "wave_grid.hpp"

namespace chladni::precompute::wave {

std::unique_ptr<Stepper> make_stepper(const WaveOptions& o) {
  return o.gpu ? make_gpu_stepper(o.gpu) : make_cpu_stepper(o.threads);
}

}  // namespace chladni::precompute::wave
