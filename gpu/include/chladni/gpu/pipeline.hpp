#pragma once
// A compute pipeline from embedded SPIR-V: storage buffers at bindings 0..n-1 of set 0, an
// optional push-constant block and uint32 specialization constants.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <span>

namespace chladni::gpu {

class Buffer;
class Context;

struct SpecConstant {
  uint32_t id;
  uint32_t value;
};

class Pipeline {
 public:
  Pipeline(Context& ctx, std::span<const uint32_t> spirv, uint32_t storage_buffers,
           uint32_t push_constant_bytes, std::span<const SpecConstant> spec = {});
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  /// Points binding `binding` at `buffer` (whole range).
  void bind(uint32_t binding, const Buffer& buffer);

  VkPipeline handle() const { return pipeline_; }
  VkPipelineLayout layout() const { return layout_; }
  VkDescriptorSet descriptor_set() const { return set_; }
  uint32_t push_constant_bytes() const { return push_bytes_; }

 private:
  Context* ctx_;
  VkShaderModule module_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  uint32_t push_bytes_ = 0;
};

}  // namespace chladni::gpu
