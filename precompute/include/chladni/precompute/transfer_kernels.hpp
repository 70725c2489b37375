#pragma once
// The dense kernels of the equivalent-source method: the collocation matrix (free-space Green's
// function G = e^(ikr) / (4 pi r) or its normal derivative) and the pressure of sources at field
// points. Two implementations: the CPU reference in double precision and the Vulkan kernels
// (kernels/xfer_*.comp, single precision). Coordinates should be relative to the object's centre
// so that float keeps them precise.
#include <complex>
#include <memory>
#include <span>
#include <string>

#include "chladni/core/vec3.hpp"

namespace chladni::gpu {
class Context;
}

namespace chladni::precompute {

class TransferKernels {
 public:
  virtual ~TransferKernels() = default;
  /// out[s * points.size() + p] = dG/dn_x(x_p, y_s) (normals given) or G(x_p, y_s) (normals
  /// empty): column-major, points x sources.
  virtual void matrix(std::span<const Vec3> points, std::span<const Vec3> normals,
                      std::span<const Vec3> sources, double k, std::complex<double>* out) = 0;
  /// out[j] = sum_s q_s G(x_j, y_s).
  virtual void field(std::span<const Vec3> points, std::span<const Vec3> sources,
                     std::span<const std::complex<double>> q, double k,
                     std::complex<double>* out) = 0;
  virtual std::string name() const = 0;
  /// Whether calls from several threads at once are safe (the CPU kernels; not one GPU queue).
  virtual bool thread_safe() const { return false; }
};

/// Double precision, threaded over columns (threads 0: all cores).
std::unique_ptr<TransferKernels> make_cpu_transfer_kernels(int threads = 0);
/// Single precision Vulkan compute on `ctx`.
std::unique_ptr<TransferKernels> make_gpu_transfer_kernels(std::shared_ptr<gpu::Context> ctx);

}  // namespace chladni::precompute
