#pragma once
// Listener gains from acoustic transfer (core/transfer.hpp): for every mode of every object,
// |p_i(listener)| per unit modal amplitude, recomputed whenever the listener or an object moves.
// The modes of many objects are flattened into one table (single precision); a CPU path
// (threaded, allocation-free per update) and a Vulkan kernel (kernels/xfer_gains.comp) evaluate
// the same series: p = sum_l [h_l(kr) / h_l(kR)] sum_m a_lm Y_lm(x^), with r clamped to >= R.
// The CPU path reads each mode's far-field map instead (gain_map.hpp) where the listener is
// beyond the map's valid radius: four grid nodes per mode instead of (L+1)^2 coefficients.
// Instances of one asset share its coefficients and maps (add_instance).
#include <complex>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "chladni/core/transfer.hpp"
#include "chladni/core/vec3.hpp"
#include "chladni/runtime/modal/gain_map.hpp"

namespace chladni::gpu {
class Buffer;
class Context;
class Pipeline;
class Sequence;
}  // namespace chladni::gpu

namespace chladni::runtime {

class ThreadPool;

struct TransferTable {
  struct Mode {
    float k;          ///< wavenumber (rad/m)
    uint32_t order;   ///< L
    uint32_t offset;  ///< first coefficient
    uint32_t object;
  };
  struct Object {
    Vec3 centre{0, 0, 0};
    double radius = 0;
    uint32_t max_order = 0;
    uint32_t first_mode = 0, mode_count = 0;
    uint32_t y_offset = 0;  ///< first Y_lm of this object in the per-update harmonics table
    uint32_t map = kNoMap;  ///< index in maps
  };
  static constexpr uint32_t kNoMap = UINT32_MAX;
  std::vector<Mode> modes;
  std::vector<std::complex<float>> coefficients;
  std::vector<Object> objects;
  std::vector<GainMap> maps;
  uint32_t y_count = 0;  ///< harmonics per update, summed over objects

  /// Options for the far-field maps built by add(); nullopt: the series everywhere.
  std::optional<GainMapOptions> map_options = GainMapOptions{};

  /// Appends an object's modes (and builds its maps, threaded over `pool` when given); returns
  /// the object's index.
  uint32_t add(const Transfer& t, ThreadPool* pool = nullptr);
  /// Another object with the same modes as `object` (another instance of the same asset): shares
  /// its coefficients and maps, so only the per-mode records are added.
  uint32_t add_instance(uint32_t object);
  std::size_t mode_count() const { return modes.size(); }
};

/// Per-update scratch: each object's clamped distance, the listener direction's cell on the
/// object's maps, and its harmonics Y_lm(listener direction) where the series is needed.
struct ListenerFrame {
  std::vector<float> r;           ///< per object
  std::vector<MapDirection> dir;  ///< per object
  std::vector<int> series_order;  ///< per object: harmonics computed up to this order (-1: none)
  std::vector<float> y;           ///< TransferTable::y_count
  bool all_harmonics = false;     ///< y holds every object's harmonics (as the GPU kernel needs)
  std::vector<double> scratch;
  /// Fills the frame from the listener's position in each object's frame (no allocation once
  /// sized). Harmonics are computed only for objects whose listener is nearer than their maps
  /// hold, unless `all_harmonics`.
  void update(const TransferTable& table, std::span<const Vec3> listener_in_object,
              bool all_harmonics = false);
};

/// CPU evaluation: out[i] = |p_i| for every mode of the table. Allocation-free; spreads the modes
/// over `pool` when given.
void transfer_gains(const TransferTable& table, const ListenerFrame& frame, std::span<float> out,
                    ThreadPool* pool = nullptr);

/// The same on a Vulkan device: coefficients stay on the device (in as many buffers as the
/// device's storage-buffer range requires); an update uploads r and Y (kilobytes), runs one
/// dispatch per buffer in one submit and reads back one float per mode.
class GpuTransferGains {
 public:
  /// `max_chunk_bytes` bounds each coefficient buffer further than the device does (tests).
  GpuTransferGains(std::shared_ptr<gpu::Context> ctx, const TransferTable& table,
                   uint64_t max_chunk_bytes = 1ull << 28);
  ~GpuTransferGains();
  void compute(const ListenerFrame& frame, std::span<float> out);
  /// Device time of the last compute() (0 without timestamps).
  double last_device_ms() const { return device_ms_; }

 private:
  std::shared_ptr<gpu::Context> ctx_;
  uint32_t modes_ = 0, y_count_ = 0, objects_ = 0;
  // Modes in chunks whose coefficients fit one storage-buffer binding of the device.
  struct Chunk {
    uint32_t first = 0, count = 0;
    std::unique_ptr<gpu::Buffer> modes, coefficients;
    std::unique_ptr<gpu::Pipeline> pipeline;
  };
  std::vector<Chunk> chunks_;
  std::unique_ptr<gpu::Buffer> object_buf_, y_buf_, out_buf_;
  std::unique_ptr<gpu::Sequence> seq_;
  double device_ms_ = 0;
};

}  // namespace chladni::runtime
