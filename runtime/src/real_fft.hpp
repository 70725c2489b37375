#pragma once
// A real FFT of size n (KISS FFT, BSD-3-clause: the runtime stays free of GPL code). Unnormalized
// both ways: inverse(forward(x)) = n x.
#include <kiss_fftr.h>

#include <string>
#include <vector>

#include "chladni/core/error.hpp"

namespace chladni::runtime {

struct RealFft {
  kiss_fftr_cfg cfg = nullptr;
  std::vector<float> real;
  std::vector<kiss_fft_cpx> spec;
  bool inverse;
  RealFft(std::size_t n, bool inv) : real(n), spec(n / 2 + 1), inverse(inv) {
    cfg = kiss_fftr_alloc(int(n), inv ? 1 : 0, nullptr, nullptr);
    if (!cfg)
      throw InternalError("KISS FFT could not plan a transform of size " + std::to_string(n));
  }
  ~RealFft() { kiss_fftr_free(cfg); }
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;
  void execute() {
    if (inverse)
      kiss_fftri(cfg, spec.data(), real.data());
    else
      kiss_fftr(cfg, real.data(), spec.data());
  }
};

}  // namespace chladni::runtime
