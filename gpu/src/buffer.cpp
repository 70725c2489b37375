#include "chladni/gpu/buffer.hpp"

#include <cstring>
#include <utility>

#include "chladni/gpu/context.hpp"
#include "chladni/gpu/sequence.hpp"

namespace chladni::gpu {

Buffer::Buffer(Context& ctx, VkDeviceSize bytes, Memory memory) : ctx_(&ctx), size_(bytes) {
  if (bytes == 0) throw Error("cannot create an empty Vulkan buffer");
  VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bi.size = bytes;
  bi.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
             VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  check(vkCreateBuffer(ctx.device(), &bi, nullptr, &buffer_), "vkCreateBuffer");
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(ctx.device(), buffer_, &req);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  if (memory == Memory::DeviceLocal) {
    ai.memoryTypeIndex =
        ctx.memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0);
  } else {
    // Cached memory makes host reads of results fast; coherent spares explicit flushes.
    ai.memoryTypeIndex =
        ctx.memory_type(req.memoryTypeBits,
                        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                        VK_MEMORY_PROPERTY_HOST_CACHED_BIT);
  }
  const VkResult r = vkAllocateMemory(ctx.device(), &ai, nullptr, &memory_);
  if (r != VK_SUCCESS) {
    vkDestroyBuffer(ctx.device(), buffer_, nullptr);
    check(r, "vkAllocateMemory");
  }
  check(vkBindBufferMemory(ctx.device(), buffer_, memory_, 0), "vkBindBufferMemory");
  if (memory == Memory::HostVisible) {
    check(vkMapMemory(ctx.device(), memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
  }
}

Buffer::Buffer(Buffer&& o) noexcept
    : ctx_(o.ctx_),
      buffer_(std::exchange(o.buffer_, VK_NULL_HANDLE)),
      memory_(std::exchange(o.memory_, VK_NULL_HANDLE)),
      size_(o.size_),
      mapped_(std::exchange(o.mapped_, nullptr)) {}

Buffer::~Buffer() {
  if (mapped_) vkUnmapMemory(ctx_->device(), memory_);
  if (buffer_) vkDestroyBuffer(ctx_->device(), buffer_, nullptr);
  if (memory_) vkFreeMemory(ctx_->device(), memory_, nullptr);
}

void Buffer::upload(const void* src, VkDeviceSize bytes, VkDeviceSize offset) {
  if (offset + bytes > size_) throw Error("Buffer::upload out of range");
  if (bytes == 0) return;
  if (mapped_) {
    std::memcpy(static_cast<char*>(mapped_) + offset, src, bytes);
    return;
  }
  Buffer staging(*ctx_, bytes, Memory::HostVisible);
  std::memcpy(staging.data(), src, bytes);
  Sequence seq(*ctx_);
  seq.begin();
  seq.copy(staging, *this, bytes, 0, offset);
  seq.barrier();
  seq.run();
}

void Buffer::download(void* dst, VkDeviceSize bytes, VkDeviceSize offset) const {
  if (offset + bytes > size_) throw Error("Buffer::download out of range");
  if (bytes == 0) return;
  if (mapped_) {
    std::memcpy(dst, static_cast<const char*>(mapped_) + offset, bytes);
    return;
  }
  Buffer staging(*ctx_, bytes, Memory::HostVisible);
  Sequence seq(*ctx_);
  seq.begin();
  seq.copy(*this, staging, bytes, offset, 0);
  seq.barrier();
  seq.run();
  std::memcpy(dst, staging.data(), bytes);
}

void Buffer::zero() {
  if (mapped_) {
    std::memset(mapped_, 0, size_);
    return;
  }
  Sequence seq(*ctx_);
  seq.begin();
  seq.fill_zero(*this);
  seq.barrier();
  seq.run();
}

}  // namespace chladni::gpu
