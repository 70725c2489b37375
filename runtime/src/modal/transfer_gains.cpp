#include "chladni/runtime/modal/transfer_gains.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "chladni/core/error.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"
#include "chladni/gpu/sequence.hpp"
#include "chladni/kernels/xfer_gains.spv.h"
#include "chladni/runtime/thread_pool.hpp"

namespace chladni::runtime {
namespace {

constexpr uint32_t kLocal = 64;  // local_size_x of xfer_gains.comp
constexpr int kModesPerTask = 2048;

// |sum_l [h_l(x) / h_l(x0)] sum_m a_lm Y_lm| with h_l = e^(ix) g_l(x) (the common phase drops out
// of the magnitude); g_l(x) = polynomial in 1/x by the upward recurrence, both sequences rescaled
// together so orders whose g_l(x0) alone would overflow float still contribute their tiny share.
float mode_gain(const TransferTable::Mode& m, const std::complex<float>* a, const float* y, float r,
                float radius) {
  // Plain float arithmetic: std::complex<float> division and abs go through __divsc3 and hypot,
  // several times slower than the products they wrap.
  const float ix = 1.0f / (m.k * r), ix0 = 1.0f / (m.k * radius);
  float g0r = 0.0f, g0i = -ix, g1r = -ix, g1i = -ix * ix;      // g_0, g_1 at kr
  float h0r = 0.0f, h0i = -ix0, h1r = -ix0, h1i = -ix0 * ix0;  // g_0, g_1 at kR
  float pr = 0.0f, pi = 0.0f;
  const int L = static_cast<int>(m.order);
  for (int l = 0; l <= L; ++l) {
    if (l >= 2) {
      const float f = float(2 * l - 1);
      const float g2r = f * ix * g1r - g0r, g2i = f * ix * g1i - g0i;
      const float h2r = f * ix0 * h1r - h0r, h2i = f * ix0 * h1i - h0i;
      g0r = g1r, g0i = g1i, g1r = g2r, g1i = g2i;
      h0r = h1r, h0i = h1i, h1r = h2r, h1i = h2i;
      if (std::abs(h1r) + std::abs(h1i) > 1e15f) {
        g0r *= 1e-15f, g0i *= 1e-15f, g1r *= 1e-15f, g1i *= 1e-15f;
        h0r *= 1e-15f, h0i *= 1e-15f, h1r *= 1e-15f, h1i *= 1e-15f;
      }
    }
    const float gr = l == 0 ? g0r : g1r, gi = l == 0 ? g0i : g1i;
    const float hr = l == 0 ? h0r : h1r, hi = l == 0 ? h0i : h1i;
    const float inv = 1.0f / (hr * hr + hi * hi);
    const float qr = (gr * hr + gi * hi) * inv, qi = (gi * hr - gr * hi) * inv;  // g / h
    float sr = 0.0f, si = 0.0f;
    const std::size_t base = std::size_t(l) * std::size_t(l);
    for (int k = 0; k <= 2 * l; ++k) {
      sr += a[base + k].real() * y[base + k];
      si += a[base + k].imag() * y[base + k];
    }
    pr += qr * sr - qi * si;
    pi += qr * si + qi * sr;
  }
  return std::sqrt(pr * pr + pi * pi);
}

struct CpuTask {
  const TransferTable* table;
  const ListenerFrame* frame;
  float* out;
};

void object_gains(const TransferTable& t, const ListenerFrame& f, uint32_t o, float* out) {
  const TransferTable::Object& ob = t.objects[o];
  const float r = f.r[o];
  float* dst = out + ob.first_mode;
  if (ob.map == TransferTable::kNoMap) {
    for (uint32_t j = 0; j < ob.mode_count; ++j) {
      const TransferTable::Mode& m = t.modes[ob.first_mode + j];
      dst[j] = mode_gain(m, t.coefficients.data() + m.offset, f.y.data() + ob.y_offset, r,
                         float(ob.radius));
    }
    return;
  }
  const GainMap& map = t.maps[ob.map];
  for (const GainMap::Grid& g : map.grids) grid_gains(g, g.cell(f.dir[o]), 1.0f / r, dst);
  if (f.series_order[o] < 0) return;
  for (uint32_t j = 0; j < ob.mode_count; ++j) {
    if (r >= map.valid_radius[j]) continue;
    const TransferTable::Mode& m = t.modes[ob.first_mode + j];
    dst[j] = mode_gain(m, t.coefficients.data() + m.offset, f.y.data() + ob.y_offset, r,
                       float(ob.radius));
  }
}

// Task i: the objects whose first mode lies in [i K, (i + 1) K), K = kModesPerTask.
void cpu_task(void* ctx, int index) {
  const auto& c = *static_cast<const CpuTask*>(ctx);
  const auto& objs = c.table->objects;
  auto first_at = [&](std::size_t mode) {
    return std::lower_bound(
               objs.begin(), objs.end(), mode,
               [](const TransferTable::Object& o, std::size_t m) { return o.first_mode < m; }) -
           objs.begin();
  };
  const std::size_t b = first_at(std::size_t(index) * kModesPerTask);
  const std::size_t e = first_at(std::size_t(index + 1) * kModesPerTask);
  for (std::size_t o = b; o < e; ++o) object_gains(*c.table, *c.frame, uint32_t(o), c.out);
}

struct GpuMode {
  float k;
  uint32_t order, offset, object;
};
struct GpuObject {
  float r, radius;
  uint32_t y_offset, pad;
};
struct Push {
  uint32_t mode_count, first_mode;
};

}  // namespace

uint32_t TransferTable::add(const Transfer& t, ThreadPool* pool) {
  t.validate();
  Object o;
  o.centre = t.centre;
  o.radius = t.radius;
  o.first_mode = static_cast<uint32_t>(modes.size());
  o.mode_count = static_cast<uint32_t>(t.mode_count());
  o.y_offset = y_count;
  const uint32_t index = static_cast<uint32_t>(objects.size());
  for (std::size_t i = 0; i < t.mode_count(); ++i) {
    const ModeTransfer& mt = t.modes[i];
    const std::size_t n = sh_count(static_cast<int>(mt.order));
    if (coefficients.size() + n > UINT32_MAX)
      throw InputError("transfer table: too many coefficients");
    modes.push_back({static_cast<float>(mt.wavenumber), mt.order,
                     static_cast<uint32_t>(coefficients.size()), index});
    const std::complex<float>* a = t.coefficients_of(i);
    coefficients.insert(coefficients.end(), a, a + n);
    o.max_order = std::max(o.max_order, mt.order);
  }
  if (map_options && t.mode_count() > 0) {
    maps.push_back(build_gain_map(t, *map_options, pool));
    o.map = static_cast<uint32_t>(maps.size() - 1);
  }
  y_count += static_cast<uint32_t>(sh_count(static_cast<int>(o.max_order)));
  objects.push_back(o);
  return index;
}

uint32_t TransferTable::add_instance(uint32_t object) {
  if (object >= objects.size()) throw std::out_of_range("transfer table: no such object");
  Object o = objects[object];
  const uint32_t index = static_cast<uint32_t>(objects.size());
  const uint32_t first = o.first_mode;
  o.first_mode = static_cast<uint32_t>(modes.size());
  o.y_offset = y_count;
  for (uint32_t i = 0; i < o.mode_count; ++i) {
    Mode m = modes[first + i];
    m.object = index;
    modes.push_back(m);
  }
  y_count += static_cast<uint32_t>(sh_count(static_cast<int>(o.max_order)));
  objects.push_back(o);
  return index;
}

void ListenerFrame::update(const TransferTable& table, std::span<const Vec3> listener,
                           bool every_object) {
  if (listener.size() != table.objects.size())
    throw std::invalid_argument("listener frame: one position per object is required");
  r.resize(table.objects.size());
  dir.resize(table.objects.size());
  series_order.resize(table.objects.size());
  y.resize(table.y_count);
  all_harmonics = every_object;
  uint32_t top = 0;
  for (const auto& ob : table.objects) top = std::max(top, ob.max_order);
  scratch.resize(sh_count(static_cast<int>(top)));
  double* yd = scratch.data();
  for (std::size_t o = 0; o < table.objects.size(); ++o) {
    const TransferTable::Object& ob = table.objects[o];
    const Vec3 d = sub(listener[o], ob.centre);
    r[o] = static_cast<float>(std::max(std::sqrt(dot(d, d)), ob.radius));
    dir[o] = map_direction(d);
    // Harmonics only up to the highest order the series still has to serve at this distance.
    int order = static_cast<int>(ob.max_order);
    if (ob.map != TransferTable::kNoMap && !every_object)
      order = table.maps[ob.map].series_order(r[o]);
    series_order[o] = order;
    if (order < 0) continue;
    real_sh(order, d, yd);
    for (std::size_t k = 0; k < sh_count(order); ++k)
      y[ob.y_offset + k] = static_cast<float>(yd[k]);
  }
}

void transfer_gains(const TransferTable& table, const ListenerFrame& frame, std::span<float> out,
                    ThreadPool* pool) {
  if (out.size() < table.modes.size())
    throw std::invalid_argument("transfer gains: output too short");
  if (frame.r.size() != table.objects.size())
    throw std::invalid_argument("transfer gains: frame does not match the table");
  CpuTask task{&table, &frame, out.data()};
  const int tasks = static_cast<int>((table.modes.size() + kModesPerTask - 1) / kModesPerTask);
  if (pool)
    pool->run(cpu_task, &task, tasks);
  else
    for (int i = 0; i < tasks; ++i) cpu_task(&task, i);
}

GpuTransferGains::GpuTransferGains(std::shared_ptr<gpu::Context> ctx, const TransferTable& t,
                                   uint64_t max_chunk_bytes)
    : ctx_(std::move(ctx)),
      modes_(static_cast<uint32_t>(t.modes.size())),
      y_count_(t.y_count),
      objects_(static_cast<uint32_t>(t.objects.size())) {
  if (!ctx_) throw std::invalid_argument("GpuTransferGains needs a Vulkan context");
  const uint64_t range = std::min<uint64_t>(ctx_->limits().maxStorageBufferRange, max_chunk_bytes);
  auto device = [&](const void* data, std::size_t bytes) {
    auto b = std::make_unique<gpu::Buffer>(*ctx_, std::max<std::size_t>(bytes, 16),
                                           gpu::Memory::DeviceLocal);
    if (bytes > 0) b->upload(data, bytes);
    return b;
  };
  auto host = [&](std::size_t bytes) {
    if (bytes > ctx_->limits().maxStorageBufferRange)
      throw gpu::Error("transfer gains: per-update data exceeds a buffer binding");
    return std::make_unique<gpu::Buffer>(*ctx_, std::max<std::size_t>(bytes, 16),
                                         gpu::Memory::HostVisible);
  };
  // Per-update inputs and the result are host-visible: small, written and read every update.
  object_buf_ = host(objects_ * sizeof(GpuObject));
  y_buf_ = host(y_count_ * sizeof(float));
  out_buf_ = host(modes_ * sizeof(float));
  auto* objs = static_cast<GpuObject*>(object_buf_->data());
  for (uint32_t o = 0; o < objects_; ++o)
    objs[o] = {0.0f, float(t.objects[o].radius), t.objects[o].y_offset, 0u};

  // A chunk's modes read one contiguous coefficient range; instances point back into their
  // asset's range, so the range is the span of all offsets in the chunk.
  const uint64_t max_coeffs = range / sizeof(std::complex<float>);
  auto end_of = [&](uint32_t i) { return t.modes[i].offset + sh_count(int(t.modes[i].order)); };
  for (uint32_t first = 0; first < modes_;) {
    Chunk c;
    c.first = first;
    uint64_t lo = t.modes[first].offset, hi = end_of(first);
    if (hi - lo > max_coeffs) throw gpu::Error("transfer gains: one mode exceeds a buffer binding");
    uint32_t i = first + 1;
    for (; i < modes_; ++i) {
      const uint64_t l2 = std::min<uint64_t>(lo, t.modes[i].offset), h2 = std::max(hi, end_of(i));
      if (h2 - l2 > max_coeffs) break;
      lo = l2, hi = h2;
    }
    c.count = i - first;
    if ((uint64_t(c.count) + kLocal - 1) / kLocal > ctx_->limits().maxComputeWorkGroupCount[0])
      throw gpu::Error("transfer gains: too many modes for one dispatch");
    std::vector<GpuMode> modes;
    for (uint32_t m = first; m < i; ++m)
      modes.push_back(
          {t.modes[m].k, t.modes[m].order, uint32_t(t.modes[m].offset - lo), t.modes[m].object});
    c.modes = device(modes.data(), modes.size() * sizeof(GpuMode));
    c.coefficients = device(t.coefficients.data() + lo, (hi - lo) * sizeof(std::complex<float>));
    c.pipeline = std::make_unique<gpu::Pipeline>(*ctx_, k_xfer_gains_spv, 5, sizeof(Push));
    c.pipeline->bind(0, *c.modes);
    c.pipeline->bind(1, *c.coefficients);
    c.pipeline->bind(2, *object_buf_);
    c.pipeline->bind(3, *y_buf_);
    c.pipeline->bind(4, *out_buf_);
    chunks_.push_back(std::move(c));
    first = i;
  }
  seq_ = std::make_unique<gpu::Sequence>(*ctx_, 2);
}

GpuTransferGains::~GpuTransferGains() = default;

void GpuTransferGains::compute(const ListenerFrame& frame, std::span<float> out) {
  if (out.size() < modes_) throw std::invalid_argument("transfer gains: output too short");
  if (frame.r.size() != objects_ || frame.y.size() != y_count_)
    throw std::invalid_argument("transfer gains: frame does not match the table");
  if (!frame.all_harmonics)
    throw std::invalid_argument("transfer gains: the GPU series needs every object's harmonics");
  if (modes_ == 0) return;
  auto* objs = static_cast<GpuObject*>(object_buf_->data());
  for (uint32_t o = 0; o < objects_; ++o) objs[o].r = frame.r[o];
  std::copy(frame.y.begin(), frame.y.end(), static_cast<float*>(y_buf_->data()));
  seq_->begin();
  seq_->timestamp(0);
  for (const Chunk& c : chunks_) {
    const Push push{c.count, c.first};
    seq_->dispatch(*c.pipeline, (c.count + kLocal - 1) / kLocal, &push, sizeof push);
  }
  seq_->timestamp(1);
  seq_->barrier();
  seq_->run();
  device_ms_ = seq_->elapsed_ns(0, 1) * 1e-6;
  const float* src = static_cast<const float*>(out_buf_->data());
  std::copy(src, src + modes_, out.begin());
}

}  // namespace chladni::runtime
