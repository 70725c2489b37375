#include "chladni/gpu/sequence.hpp"

#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"

namespace chladni::gpu {

Sequence::Sequence(Context& ctx, uint32_t timestamp_slots) : ctx_(&ctx) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = ctx.command_pool();
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  check(vkAllocateCommandBuffers(ctx.device(), &ai, &cmd_), "vkAllocateCommandBuffers");
  VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  check(vkCreateFence(ctx.device(), &fi, nullptr, &fence_), "vkCreateFence");
  if (timestamp_slots && ctx.timestamps()) {
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qi.queryCount = timestamp_slots;
    check(vkCreateQueryPool(ctx.device(), &qi, nullptr, &queries_), "vkCreateQueryPool");
    slots_ = timestamp_slots;
  }
}

Sequence::~Sequence() {
  if (pending_) vkWaitForFences(ctx_->device(), 1, &fence_, VK_TRUE, UINT64_MAX);
  if (queries_) vkDestroyQueryPool(ctx_->device(), queries_, nullptr);
  vkDestroyFence(ctx_->device(), fence_, nullptr);
  vkFreeCommandBuffers(ctx_->device(), ctx_->command_pool(), 1, &cmd_);
}

void Sequence::begin() {
  if (pending_) wait();
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(cmd_, &bi), "vkBeginCommandBuffer");
  if (queries_) vkCmdResetQueryPool(cmd_, queries_, 0, slots_);
  recording_ = true;
}

void Sequence::dispatch(const Pipeline& p, uint32_t groups_x, const void* push, uint32_t push_bytes,
                        uint32_t groups_y) {
  vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
  VkDescriptorSet set = p.descriptor_set();
  vkCmdBindDescriptorSets(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, p.layout(), 0, 1, &set, 0, nullptr);
  if (push_bytes) {
    vkCmdPushConstants(cmd_, p.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, push_bytes, push);
  }
  if (groups_x && groups_y) vkCmdDispatch(cmd_, groups_x, groups_y, 1);
}

void Sequence::copy(const Buffer& src, const Buffer& dst, VkDeviceSize bytes,
                    VkDeviceSize src_offset, VkDeviceSize dst_offset) {
  VkBufferCopy region{src_offset, dst_offset, bytes};
  vkCmdCopyBuffer(cmd_, src.handle(), dst.handle(), 1, &region);
}

void Sequence::fill_zero(const Buffer& dst) {
  vkCmdFillBuffer(cmd_, dst.handle(), 0, VK_WHOLE_SIZE, 0);
}

void Sequence::barrier() {
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                     VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT |
                     VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                           VK_PIPELINE_STAGE_HOST_BIT,
                       0, 1, &mb, 0, nullptr, 0, nullptr);
}

void Sequence::timestamp(uint32_t slot) {
  if (queries_ && slot < slots_) {
    vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries_, slot);
  }
}

void Sequence::submit() {
  if (!recording_) throw Error("Sequence::submit without begin");
  check(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer");
  recording_ = false;
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd_;
  ctx_->submit(si, fence_);
  pending_ = true;
}

void Sequence::wait() {
  if (!pending_) return;
  check(vkWaitForFences(ctx_->device(), 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
  check(vkResetFences(ctx_->device(), 1, &fence_), "vkResetFences");
  pending_ = false;
}

double Sequence::elapsed_ns(uint32_t from_slot, uint32_t to_slot) const {
  if (!queries_ || from_slot >= slots_ || to_slot >= slots_) return 0.0;
  uint64_t a = 0, b = 0;
  if (vkGetQueryPoolResults(ctx_->device(), queries_, from_slot, 1, sizeof(uint64_t), &a,
                            sizeof(uint64_t), VK_QUERY_RESULT_64_BIT) != VK_SUCCESS ||
      vkGetQueryPoolResults(ctx_->device(), queries_, to_slot, 1, sizeof(uint64_t), &b,
                            sizeof(uint64_t), VK_QUERY_RESULT_64_BIT) != VK_SUCCESS) {
    return 0.0;
  }
  // Counters wrap at timestampValidBits: subtract modulo the valid range.
  const uint64_t mask = ctx_->timestamp_mask();
  return static_cast<double>((b - a) & mask) * ctx_->timestamp_period_ns();
}

}  // namespace chladni::gpu
