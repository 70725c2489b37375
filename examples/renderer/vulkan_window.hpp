#pragma once
// A window drawn with Vulkan through SDL2: the renderer a game would have. It makes the instance
// and the device (one queue family for graphics, presenting and compute), draws coloured
// rectangles each frame (vkCmdClearAttachments: no shaders to ship), and can read a frame back.
// The queue is shared with the audio runtime, so every submit and present holds `queue_lock`.
#include <SDL.h>
#include <vulkan/vulkan.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

struct Rect {
  int x, y, w, h;  // pixels, y down
  float rgba[4];
};

class VulkanWindow {
 public:
  VulkanWindow(const char* title, int width, int height);
  ~VulkanWindow();
  VulkanWindow(const VulkanWindow&) = delete;
  VulkanWindow& operator=(const VulkanWindow&) = delete;

  /// Clears to `background` and fills `rects`; with `capture`, reads the frame back into
  /// `captured` (RGB, row by row) before presenting it.
  void draw(const float background[4], const std::vector<Rect>& rects, bool capture);
  int width() const { return int(extent_.width); }
  int height() const { return int(extent_.height); }

  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t family = 0;
  VkQueue queue = VK_NULL_HANDLE;
  std::mutex queue_lock;
  std::vector<uint8_t> captured;
  std::string device_name;

 private:
  void make_device();
  void make_swapchain();
  void make_pass();
  void make_commands();
  void make_capture_buffer();
  void record(uint32_t index, const float background[4], const std::vector<Rect>& rects,
              bool capture);
  void submit_and_present(uint32_t index);
  void read_back();

  SDL_Window* window_ = nullptr;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkExtent2D extent_{};
  VkRenderPass pass_ = VK_NULL_HANDLE;
  std::vector<VkImage> images_;
  std::vector<VkImageView> views_;
  std::vector<VkFramebuffer> framebuffers_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkSemaphore acquired_ = VK_NULL_HANDLE, rendered_ = VK_NULL_HANDLE;
  VkFence done_ = VK_NULL_HANDLE;
  VkBuffer readback_ = VK_NULL_HANDLE;
  VkDeviceMemory readback_memory_ = VK_NULL_HANDLE;
};
