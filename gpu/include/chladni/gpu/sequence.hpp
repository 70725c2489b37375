#pragma once
// A recorded command buffer with its fence and an optional timestamp query pool: record
// dispatches, copies and barriers, submit, wait, read GPU-side times.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <vector>

namespace chladni::gpu {

class Buffer;
class Context;
class Pipeline;

class Sequence {
 public:
  explicit Sequence(Context& ctx, uint32_t timestamp_slots = 0);
  ~Sequence();
  Sequence(const Sequence&) = delete;
  Sequence& operator=(const Sequence&) = delete;

  /// Starts recording (waits for a previous submit first).
  void begin();
  void dispatch(const Pipeline& p, uint32_t groups_x, const void* push = nullptr,
                uint32_t push_bytes = 0, uint32_t groups_y = 1);
  void copy(const Buffer& src, const Buffer& dst, VkDeviceSize bytes, VkDeviceSize src_offset = 0,
            VkDeviceSize dst_offset = 0);
  void fill_zero(const Buffer& dst);
  /// Makes earlier shader and transfer writes visible to later shaders, transfers and the host.
  void barrier();
  /// Writes a GPU timestamp into `slot` (ignored when the queue has no timestamps).
  void timestamp(uint32_t slot);
  void submit();
  void wait();
  void run() {
    submit();
    wait();
  }
  bool pending() const { return pending_; }
  /// Nanoseconds between two timestamp slots of the last completed submit (0 if unsupported).
  double elapsed_ns(uint32_t from_slot, uint32_t to_slot) const;

 private:
  Context* ctx_;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  VkQueryPool queries_ = VK_NULL_HANDLE;
  uint32_t slots_ = 0;
  bool recording_ = false;
  bool pending_ = false;
};

}  // namespace chladni::gpu
