// The centroid-rule rows of the Burton-Miller system on a Vulkan device (kernels/bem_far.comp),
// in float; bem_far_row.cpp is the double-precision reference the tests hold it to.
#include <algorithm>

#include "bem_kernels.hpp"
#include "chladni/core/error.hpp"
#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"
#include "chladni/gpu/sequence.hpp"
#include "chladni/kernels/bem_far.spv.h"
#include "chladni/precompute/bem.hpp"

namespace chladni::precompute {
namespace {

constexpr uint32_t kLocal = 64;  // local_size_x of bem_far.comp

struct Push {
  uint32_t n, row0, n_rows, rhs_pass;
  float k, al;
};

}  // namespace

struct BemGpuRows::Impl {
  std::shared_ptr<gpu::Context> ctx;
  gpu::Pipeline pipeline;
  gpu::Sequence seq;
  std::size_t n = 0;
  std::unique_ptr<gpu::Buffer> centroids, normals, q, entries, rhs;

  Impl(std::shared_ptr<gpu::Context> c, const BemMesh& m)
      : ctx(std::move(c)),
        pipeline(*ctx, k_bem_far_spv, 5, sizeof(Push)),
        seq(*ctx),
        n(m.elements()) {
    std::vector<float> cw(4 * n), nw(4 * n);
    for (std::size_t j = 0; j < n; ++j) {
      for (int a = 0; a < 3; ++a) {
        cw[4 * j + a] = float(m.centroid[j][a]);
        nw[4 * j + a] = float(m.normal[j][a]);
      }
      cw[4 * j + 3] = float(m.area[j] / (4 * std::numbers::pi));
    }
    centroids = upload(cw);
    normals = upload(nw);
  }
  std::unique_ptr<gpu::Buffer> upload(const std::vector<float>& v) {
    auto b = std::make_unique<gpu::Buffer>(*ctx, std::max<std::size_t>(v.size() * 4, 256),
                                           gpu::Memory::DeviceLocal);
    b->upload(v.data(), v.size() * sizeof(float));
    return b;
  }
  void reserve(std::unique_ptr<gpu::Buffer>& b, std::size_t bytes) {
    if (!b || b->size() < bytes)
      b = std::make_unique<gpu::Buffer>(*ctx, std::max<std::size_t>(bytes, 256),
                                        gpu::Memory::DeviceLocal);
  }
};

BemGpuRows::BemGpuRows(std::shared_ptr<gpu::Context> ctx, const BemMesh& mesh) {
  if (!ctx) throw InternalError("bem: no Vulkan context");
  impl_ = std::make_unique<Impl>(std::move(ctx), mesh);
}

BemGpuRows::~BemGpuRows() = default;

std::size_t BemGpuRows::block_rows() const {
  const uint64_t range = impl_->ctx->limits().maxStorageBufferRange;
  const uint64_t per_row = uint64_t(impl_->n) * 2 * sizeof(float);
  const uint64_t groups = impl_->ctx->limits().maxComputeWorkGroupCount[1];
  return std::size_t(std::max<uint64_t>(1, std::min<uint64_t>({range / per_row, groups, 4096})));
}

void BemGpuRows::rows(double k, double al, std::span<const std::complex<double>> q,
                      std::size_t row0, std::size_t count,
                      std::vector<std::complex<float>>& entries,
                      std::vector<std::complex<float>>& rhs) {
  Impl& s = *impl_;
  if (q.size() != s.n || row0 + count > s.n || count > block_rows())
    throw InternalError("bem: bad GPU row block");
  std::vector<float> qf(2 * s.n);
  for (std::size_t j = 0; j < s.n; ++j)
    qf[2 * j] = float(q[j].real()), qf[2 * j + 1] = float(q[j].imag());
  s.reserve(s.q, qf.size() * sizeof(float));
  s.q->upload(qf.data(), qf.size() * sizeof(float));
  s.reserve(s.entries, count * s.n * 2 * sizeof(float));
  s.reserve(s.rhs, count * 2 * sizeof(float));
  s.pipeline.bind(0, *s.centroids);
  s.pipeline.bind(1, *s.normals);
  s.pipeline.bind(2, *s.q);
  s.pipeline.bind(3, *s.entries);
  s.pipeline.bind(4, *s.rhs);
  Push entry_push{uint32_t(s.n), uint32_t(row0), uint32_t(count), 0u, float(k), float(al)};
  Push rhs_push = entry_push;
  rhs_push.rhs_pass = 1;
  s.seq.begin();
  s.seq.dispatch(s.pipeline, uint32_t((s.n + kLocal - 1) / kLocal), &entry_push, sizeof entry_push,
                 uint32_t(count));
  s.seq.dispatch(s.pipeline, uint32_t((count + kLocal - 1) / kLocal), &rhs_push, sizeof rhs_push);
  s.seq.barrier();
  s.seq.run();
  entries.resize(count * s.n);
  rhs.resize(count);
  s.entries->download(entries.data(), entries.size() * sizeof(std::complex<float>));
  s.rhs->download(rhs.data(), rhs.size() * sizeof(std::complex<float>));
}

}  // namespace chladni::precompute
