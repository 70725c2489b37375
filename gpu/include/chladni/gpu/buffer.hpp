#pragma once
// A VkBuffer with its memory. Device-local buffers are filled and read through a staging buffer;
// host-visible ones are persistently mapped (coherent).
#include <vulkan/vulkan.h>

#include <cstddef>

namespace chladni::gpu {

class Context;

enum class Memory {
  DeviceLocal,  ///< fastest for the device; transfers go through staging
  HostVisible,  ///< mapped, coherent; for small per-block uploads and read-backs
};

class Buffer {
 public:
  Buffer(Context& ctx, VkDeviceSize bytes, Memory memory);
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&&) = delete;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  VkBuffer handle() const { return buffer_; }
  VkDeviceSize size() const { return size_; }
  bool mapped() const { return mapped_ != nullptr; }
  /// Host pointer of a HostVisible buffer (nullptr for DeviceLocal).
  void* data() const { return mapped_; }

  /// Copies host data in (through a staging buffer and a blocking submit when not mapped).
  void upload(const void* src, VkDeviceSize bytes, VkDeviceSize offset = 0);
  /// Copies data out to the host (likewise).
  void download(void* dst, VkDeviceSize bytes, VkDeviceSize offset = 0) const;
  /// Fills with zero bytes.
  void zero();

 private:
  Context* ctx_;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkDeviceSize size_ = 0;
  void* mapped_ = nullptr;
};

}  // namespace chladni::gpu
