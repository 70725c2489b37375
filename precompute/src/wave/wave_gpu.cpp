// The Vulkan stepper: the grid lives on the device for the whole run; each submit records a
// batch of steps (velocity, blocked faces, pressure, and a sample where due) and the samples come
// back when their buffer fills. Four storage buffers per kernel, the least Vulkan guarantees.
#include <algorithm>
#include <numeric>

#include "chladni/core/error.hpp"
#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"
#include "chladni/gpu/sequence.hpp"
#include "chladni/kernels/wave_blocked.spv.h"
#include "chladni/kernels/wave_pressure.spv.h"
#include "chladni/kernels/wave_record.spv.h"
#include "chladni/kernels/wave_velocity.spv.h"
#include "wave_grid.hpp"

namespace chladni::precompute::wave {
namespace {

constexpr uint32_t kLocal = 256;
constexpr std::size_t kStepsPerSubmit = 64;

struct Push {
  uint32_t n[4], pml_lo[4], pml_hi[4], extra[4];
  float lambda;
  uint32_t groups_x;
};

class GpuStepper final : public Stepper {
 public:
  explicit GpuStepper(std::shared_ptr<gpu::Context> ctx)
      : ctx_(std::move(ctx)),
        velocity_(*ctx_, k_wave_velocity_spv, 3, sizeof(Push)),
        blocked_(*ctx_, k_wave_blocked_spv, 4, sizeof(Push)),
        pressure_(*ctx_, k_wave_pressure_spv, 4, sizeof(Push)),
        record_(*ctx_, k_wave_record_spv, 4, sizeof(Push)),
        seq_(*ctx_) {}

  void run(const Problem& P, std::vector<float>& samples,
           const std::function<void(std::size_t)>& progress) override {
    const Grid& g = P.grid;
    const std::size_t N = g.cells(), J = P.series, nf = P.blocked.size(), nr = P.record.size();
    const uint64_t range = ctx_->limits().maxStorageBufferRange;
    if (3 * N * sizeof(float) > range || 3 * N > UINT32_MAX)
      throw gpu::Error("wave: a grid of " + std::to_string(N) + " cells exceeds " +
                       ctx_->info().name + "'s storage-buffer range");
    auto buffer = [&](std::size_t bytes) {
      return std::make_unique<gpu::Buffer>(*ctx_, std::max<std::size_t>(bytes, 16),
                                           gpu::Memory::DeviceLocal);
    };
    auto p = buffer(N * 4), split = buffer(2 * N * 4), w = buffer(3 * N * 4);
    std::vector<float> coef;
    for (int a = 0; a < 3; ++a)
      for (const auto* v : {&P.pa[a], &P.pb[a], &P.wa[a], &P.wb[a]})
        coef.insert(coef.end(), v->begin(), v->end());
    auto coefs = upload(coef);
    std::vector<uint32_t> faces(std::max<std::size_t>(nf, 1), 0);
    for (std::size_t f = 0; f < nf; ++f)
      faces[f] = uint32_t(P.blocked.axis[f] * N + P.blocked.cell[f]);
    auto face_buf = upload(faces), amp = upload(P.amplitude), drive = upload(P.drive);
    std::vector<uint32_t> rec(2 * std::max<std::size_t>(nr, 1), 0);
    for (std::size_t q = 0; q < nr; ++q) {
      rec[2 * q] = uint32_t(P.record.axis[q] * N + P.record.cell[q]);
      rec[2 * q + 1] = uint32_t(g.stride(int(P.record.axis[q])));
    }
    auto rec_buf = upload(rec);
    const std::size_t ns = P.samples();
    const std::size_t chunk =
        std::max<std::size_t>(1, std::min<std::size_t>(ns, range / (nr * 8 + 8)));
    auto out = buffer(chunk * nr * 8);
    seq_.begin();
    seq_.fill_zero(*p), seq_.fill_zero(*split), seq_.fill_zero(*w);
    seq_.barrier();
    seq_.run();
    velocity_.bind(0, *p), velocity_.bind(1, *w), velocity_.bind(2, *coefs);
    blocked_.bind(0, *face_buf), blocked_.bind(1, *amp), blocked_.bind(2, *drive),
        blocked_.bind(3, *w);
    pressure_.bind(0, *p), pressure_.bind(1, *split), pressure_.bind(2, *w),
        pressure_.bind(3, *coefs);
    record_.bind(0, *rec_buf), record_.bind(1, *p), record_.bind(2, *w), record_.bind(3, *out);

    Push base{};
    for (int a = 0; a < 3; ++a)
      base.n[a] = g.n[a], base.pml_lo[a] = P.pml_lo[a], base.pml_hi[a] = P.pml_hi[a];
    base.n[3] = uint32_t(N);
    base.lambda = P.pb[0][P.pml_lo[0]];
    samples.assign(ns * nr * 2, 0.0f);
    std::size_t slot = 0, taken = 0;
    for (std::size_t n0 = 0; n0 < P.steps;) {
      seq_.begin();
      std::size_t n = n0;
      for (; n < P.steps && n < n0 + kStepsPerSubmit && slot < chunk; ++n) {
        dispatch(velocity_, base, N, {});
        dispatch(blocked_, base, nf, {uint32_t(nf), uint32_t(J), uint32_t(n), 0});
        dispatch(pressure_, base, N, {});
        if (n >= P.first_sample && (n - P.first_sample) % P.stride == 0) {
          dispatch(record_, base, nr, {uint32_t(nr), uint32_t(slot), 0, 0});
          ++slot;
        }
      }
      seq_.run();
      if (slot == chunk || n == P.steps) {
        out->download(samples.data() + taken * nr * 2, slot * nr * 8);
        taken += slot, slot = 0;
      }
      n0 = n;
      if (progress) progress(n0);
    }
  }

  std::string name() const override { return "gpu (" + ctx_->info().name + ", float)"; }

 private:
  template <class T>
  std::unique_ptr<gpu::Buffer> upload(const std::vector<T>& v) {
    auto b = std::make_unique<gpu::Buffer>(*ctx_, std::max<std::size_t>(v.size() * sizeof(T), 16),
                                           gpu::Memory::DeviceLocal);
    if (!v.empty()) b->upload(v.data(), v.size() * sizeof(T));
    return b;
  }

  void dispatch(gpu::Pipeline& pipe, Push push, std::size_t count, std::array<uint32_t, 4> extra) {
    if (count == 0) return;
    const uint64_t groups = (count + kLocal - 1) / kLocal;
    const uint64_t most = ctx_->limits().maxComputeWorkGroupCount[0];
    const uint64_t gx = std::min(groups, most), gy = (groups + gx - 1) / gx;
    if (gy > ctx_->limits().maxComputeWorkGroupCount[1])
      throw gpu::Error("wave: too many cells for one dispatch on " + ctx_->info().name);
    for (int q = 0; q < 4; ++q) push.extra[q] = extra[std::size_t(q)];
    push.groups_x = uint32_t(gx);
    seq_.dispatch(pipe, uint32_t(gx), &push, sizeof push, uint32_t(gy));
    seq_.barrier();
  }

  std::shared_ptr<gpu::Context> ctx_;
  gpu::Pipeline velocity_, blocked_, pressure_, record_;
  gpu::Sequence seq_;
};

}  // namespace

std::unique_ptr<Stepper> make_gpu_stepper(std::shared_ptr<gpu::Context> ctx) {
  if (!ctx) throw InternalError("wave: no Vulkan context");
  return std::make_unique<GpuStepper>(std::move(ctx));
}

}  // namespace chladni::precompute::wave
