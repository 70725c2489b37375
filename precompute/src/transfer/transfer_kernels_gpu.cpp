#include <algorithm>
#include <vector>

#include "chladni/core/error.hpp"
#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"
#include "chladni/gpu/sequence.hpp"
#include "chladni/kernels/xfer_field.spv.h"
#include "chladni/kernels/xfer_matrix.spv.h"
#include "chladni/precompute/transfer_kernels.hpp"

namespace chladni::precompute {
namespace {

constexpr uint32_t kLocal = 64;  // local_size_x of the xfer kernels

struct MatrixPush {
  uint32_t n_points, n_sources;
  float k;
  uint32_t neumann;
};
struct FieldPush {
  uint32_t n_points, n_sources;
  float k;
};

std::vector<float> as_vec4(std::span<const Vec3> v) {
  std::vector<float> out(4 * std::max<std::size_t>(v.size(), 1), 0.0f);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int c = 0; c < 3; ++c) out[4 * i + c] = static_cast<float>(v[i][c]);
  return out;
}

class GpuTransferKernels final : public TransferKernels {
 public:
  explicit GpuTransferKernels(std::shared_ptr<gpu::Context> ctx)
      : ctx_(std::move(ctx)),
        matrix_(*ctx_, k_xfer_matrix_spv, 4, sizeof(MatrixPush)),
        field_(*ctx_, k_xfer_field_spv, 4, sizeof(FieldPush)),
        seq_(*ctx_) {}

  void matrix(std::span<const Vec3> x, std::span<const Vec3> n, std::span<const Vec3> y, double k,
              std::complex<double>* out) override {
    const std::size_t np = x.size(), ns = y.size();
    if (np == 0 || ns == 0) return;
    const uint32_t groups = groups_for(np);
    const std::vector<float> xs = as_vec4(x);
    const std::vector<float> ns4 = n.empty() ? std::vector<float>(4, 0.0f) : as_vec4(n);
    put(points_, xs);
    put(normals_, ns4);
    // Columns in blocks that fit the device's storage-buffer range.
    const uint64_t range = ctx_->limits().maxStorageBufferRange;
    const std::size_t block =
        std::max<std::size_t>(1, std::min<std::size_t>(ns, range / (np * sizeof(float) * 2)));
    std::vector<float> host;
    for (std::size_t s0 = 0; s0 < ns; s0 += block) {
      const std::size_t nb = std::min(block, ns - s0);
      put(sources_, as_vec4(y.subspan(s0, nb)));
      reserve(result_, np * nb * 2 * sizeof(float));
      matrix_.bind(0, *points_);
      matrix_.bind(1, *normals_);
      matrix_.bind(2, *sources_);
      matrix_.bind(3, *result_);
      const MatrixPush push{static_cast<uint32_t>(np), static_cast<uint32_t>(nb),
                            static_cast<float>(k), n.empty() ? 0u : 1u};
      seq_.begin();
      seq_.dispatch(matrix_, groups, &push, sizeof push);
      seq_.barrier();
      seq_.run();
      host.resize(np * nb * 2);
      result_->download(host.data(), host.size() * sizeof(float));
      for (std::size_t i = 0; i < np * nb; ++i) out[s0 * np + i] = {host[2 * i], host[2 * i + 1]};
    }
  }

  void field(std::span<const Vec3> x, std::span<const Vec3> y,
             std::span<const std::complex<double>> q, double k,
             std::complex<double>* out) override {
    const std::size_t np = x.size(), ns = y.size();
    if (np == 0) return;
    const uint32_t groups = groups_for(np);
    put(points_, as_vec4(x));
    put(sources_, as_vec4(y));
    std::vector<float> qs(2 * std::max<std::size_t>(ns, 1), 0.0f);
    for (std::size_t s = 0; s < ns; ++s) {
      qs[2 * s] = static_cast<float>(q[s].real());
      qs[2 * s + 1] = static_cast<float>(q[s].imag());
    }
    put(strengths_, qs);
    reserve(result_, np * 2 * sizeof(float));
    field_.bind(0, *points_);
    field_.bind(1, *sources_);
    field_.bind(2, *strengths_);
    field_.bind(3, *result_);
    const FieldPush push{static_cast<uint32_t>(np), static_cast<uint32_t>(ns),
                         static_cast<float>(k)};
    seq_.begin();
    seq_.dispatch(field_, groups, &push, sizeof push);
    seq_.barrier();
    seq_.run();
    std::vector<float> host(np * 2);
    result_->download(host.data(), host.size() * sizeof(float));
    for (std::size_t j = 0; j < np; ++j) out[j] = {host[2 * j], host[2 * j + 1]};
  }

  std::string name() const override { return "gpu (" + ctx_->info().name + ", float)"; }

 private:
  uint32_t groups_for(std::size_t np) const {
    const uint64_t groups = (np + kLocal - 1) / kLocal;
    if (groups > ctx_->limits().maxComputeWorkGroupCount[0])
      throw InputError("transfer: too many points for one dispatch on " + ctx_->info().name);
    return static_cast<uint32_t>(groups);
  }
  void reserve(std::unique_ptr<gpu::Buffer>& b, std::size_t bytes) {
    if (!b || b->size() < bytes)
      b = std::make_unique<gpu::Buffer>(*ctx_, std::max<std::size_t>(bytes, 256),
                                        gpu::Memory::DeviceLocal);
  }
  void put(std::unique_ptr<gpu::Buffer>& b, const std::vector<float>& v) {
    reserve(b, v.size() * sizeof(float));
    b->upload(v.data(), v.size() * sizeof(float));
  }

  std::shared_ptr<gpu::Context> ctx_;
  gpu::Pipeline matrix_, field_;
  gpu::Sequence seq_;
  std::unique_ptr<gpu::Buffer> points_, normals_, sources_, strengths_, result_;
};

}  // namespace

std::unique_ptr<TransferKernels> make_gpu_transfer_kernels(std::shared_ptr<gpu::Context> ctx) {
  if (!ctx) throw InternalError("transfer: no Vulkan context");
  return std::make_unique<GpuTransferKernels>(std::move(ctx));
}

}  // namespace chladni::precompute
