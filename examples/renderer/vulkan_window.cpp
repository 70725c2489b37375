#include "vulkan_window.hpp"

#include <SDL_vulkan.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace {

void vk(VkResult r, const char* what) {
  if (r != VK_SUCCESS)
    throw std::runtime_error(std::string(what) + " failed (" + std::to_string(r) + ")");
}

}  // namespace

VulkanWindow::VulkanWindow(const char* title, int width, int height) {
  window_ = SDL_CreateWindow(title, SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, width, height,
                             SDL_WINDOW_VULKAN | SDL_WINDOW_SHOWN);
  if (!window_) throw std::runtime_error(std::string("SDL_CreateWindow: ") + SDL_GetError());
  unsigned n = 0;
  SDL_Vulkan_GetInstanceExtensions(window_, &n, nullptr);
  std::vector<const char*> extensions(n);
  if (!SDL_Vulkan_GetInstanceExtensions(window_, &n, extensions.data()))
    throw std::runtime_error(std::string("SDL_Vulkan_GetInstanceExtensions: ") + SDL_GetError());
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = title;
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  ici.enabledExtensionCount = n;
  ici.ppEnabledExtensionNames = extensions.data();
  vk(vkCreateInstance(&ici, nullptr, &instance), "vkCreateInstance");
  if (!SDL_Vulkan_CreateSurface(window_, instance, &surface_))
    throw std::runtime_error(std::string("SDL_Vulkan_CreateSurface: ") + SDL_GetError());
  make_device();
  make_swapchain();
  make_pass();
  make_commands();
  make_capture_buffer();
}

// The first device (a discrete GPU before the others) with a family that draws, presents and
// computes: the audio runtime records its compute work on the same queue.
void VulkanWindow::make_device() {
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> all(count);
  vkEnumeratePhysicalDevices(instance, &count, all.data());
  std::stable_sort(all.begin(), all.end(), [](VkPhysicalDevice a, VkPhysicalDevice b) {
    VkPhysicalDeviceProperties pa, pb;
    vkGetPhysicalDeviceProperties(a, &pa);
    vkGetPhysicalDeviceProperties(b, &pb);
    return (pa.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU) >
           (pb.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU);
  });
  for (VkPhysicalDevice p : all) {
    uint32_t nf = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(p, &nf, nullptr);
    std::vector<VkQueueFamilyProperties> families(nf);
    vkGetPhysicalDeviceQueueFamilyProperties(p, &nf, families.data());
    for (uint32_t f = 0; f < nf && !physical; ++f) {
      VkBool32 present = VK_FALSE;
      vkGetPhysicalDeviceSurfaceSupportKHR(p, f, surface_, &present);
      const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
      if (present && (families[f].queueFlags & need) == need) physical = p, family = f;
    }
    if (physical) break;
  }
  if (!physical) throw std::runtime_error("no Vulkan device draws, presents and computes");
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(physical, &props);
  device_name = props.deviceName;
  const float priority = 1;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  const char* swapchain = VK_KHR_SWAPCHAIN_EXTENSION_NAME;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = 1;
  dci.ppEnabledExtensionNames = &swapchain;
  vk(vkCreateDevice(physical, &dci, nullptr, &device), "vkCreateDevice");
  vkGetDeviceQueue(device, family, 0, &queue);
}

void VulkanWindow::make_swapchain() {
  VkSurfaceCapabilitiesKHR caps;
  vkGetPhysicalDeviceSurfaceCapabilitiesKHR(physical, surface_, &caps);
  uint32_t nf = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(physical, surface_, &nf, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(nf);
  vkGetPhysicalDeviceSurfaceFormatsKHR(physical, surface_, &nf, formats.data());
  format_ = formats.at(0).format;
  for (const VkSurfaceFormatKHR& f : formats)
    if (f.format == VK_FORMAT_B8G8R8A8_UNORM) format_ = f.format;
  if (format_ != VK_FORMAT_B8G8R8A8_UNORM && format_ != VK_FORMAT_R8G8B8A8_UNORM)
    throw std::runtime_error("the surface offers no 8-bit RGBA format");
  extent_ = caps.currentExtent;
  if (extent_.width == 0xffffffffu) {
    int w = 0, h = 0;
    SDL_Vulkan_GetDrawableSize(window_, &w, &h);
    extent_ = {uint32_t(w), uint32_t(h)};
  }
  if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT))
    throw std::runtime_error("the swapchain's images cannot be read back");
  VkSwapchainCreateInfoKHR sci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  sci.surface = surface_;
  sci.minImageCount = std::max(2u, caps.minImageCount);
  if (caps.maxImageCount) sci.minImageCount = std::min(sci.minImageCount, caps.maxImageCount);
  sci.imageFormat = format_;
  sci.imageColorSpace = VK_COLOR_SPACE_SRGB_NONLINEAR_KHR;
  sci.imageExtent = extent_;
  sci.imageArrayLayers = 1;
  sci.imageUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  sci.preTransform = caps.currentTransform;
  sci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  sci.presentMode = VK_PRESENT_MODE_FIFO_KHR;  // always there
  sci.clipped = VK_TRUE;
  vk(vkCreateSwapchainKHR(device, &sci, nullptr, &swapchain_), "vkCreateSwapchainKHR");
  uint32_t ni = 0;
  vkGetSwapchainImagesKHR(device, swapchain_, &ni, nullptr);
  images_.resize(ni);
  vkGetSwapchainImagesKHR(device, swapchain_, &ni, images_.data());
}

void VulkanWindow::make_pass() {
  // One pass: clear, draw, and leave the image ready for a copy; a barrier then hands it over
  // for presenting.
  VkAttachmentDescription color{};
  color.format = format_;
  color.samples = VK_SAMPLE_COUNT_1_BIT;
  color.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  color.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  color.finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription sub{};
  sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  sub.colorAttachmentCount = 1;
  sub.pColorAttachments = &ref;
  VkRenderPassCreateInfo rpi{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rpi.attachmentCount = 1;
  rpi.pAttachments = &color;
  rpi.subpassCount = 1;
  rpi.pSubpasses = &sub;
  vk(vkCreateRenderPass(device, &rpi, nullptr, &pass_), "vkCreateRenderPass");
  for (VkImage image : images_) {
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = image;
    vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vci.format = format_;
    vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view;
    vk(vkCreateImageView(device, &vci, nullptr, &view), "vkCreateImageView");
    views_.push_back(view);
    VkFramebufferCreateInfo fci{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fci.renderPass = pass_;
    fci.attachmentCount = 1;
    fci.pAttachments = &view;
    fci.width = extent_.width;
    fci.height = extent_.height;
    fci.layers = 1;
    VkFramebuffer fb;
    vk(vkCreateFramebuffer(device, &fci, nullptr, &fb), "vkCreateFramebuffer");
    framebuffers_.push_back(fb);
  }
}

void VulkanWindow::make_commands() {
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = family;
  vk(vkCreateCommandPool(device, &pci, nullptr, &pool_), "vkCreateCommandPool");
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = pool_;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  vk(vkAllocateCommandBuffers(device, &cai, &cmd_), "vkAllocateCommandBuffers");
  VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  vk(vkCreateSemaphore(device, &si, nullptr, &acquired_), "vkCreateSemaphore");
  vk(vkCreateSemaphore(device, &si, nullptr, &rendered_), "vkCreateSemaphore");
  VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  vk(vkCreateFence(device, &fi, nullptr, &done_), "vkCreateFence");
}

void VulkanWindow::make_capture_buffer() {
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = VkDeviceSize(extent_.width) * extent_.height * 4;
  bci.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  vk(vkCreateBuffer(device, &bci, nullptr, &readback_), "vkCreateBuffer");
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device, readback_, &req);
  VkPhysicalDeviceMemoryProperties mem;
  vkGetPhysicalDeviceMemoryProperties(physical, &mem);
  const VkMemoryPropertyFlags want =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  uint32_t type = UINT32_MAX;
  for (uint32_t i = 0; i < mem.memoryTypeCount && type == UINT32_MAX; ++i)
    if ((req.memoryTypeBits & (1u << i)) && (mem.memoryTypes[i].propertyFlags & want) == want)
      type = i;
  if (type == UINT32_MAX) throw std::runtime_error("no host-visible memory for the read-back");
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = type;
  vk(vkAllocateMemory(device, &mai, nullptr, &readback_memory_), "vkAllocateMemory");
  vk(vkBindBufferMemory(device, readback_, readback_memory_, 0), "vkBindBufferMemory");
}

void VulkanWindow::draw(const float background[4], const std::vector<Rect>& rects, bool capture) {
  uint32_t index = 0;
  vk(vkAcquireNextImageKHR(device, swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index),
     "vkAcquireNextImageKHR");
  record(index, background, rects, capture);
  submit_and_present(index);
  if (capture) read_back();
}

void VulkanWindow::record(uint32_t index, const float background[4], const std::vector<Rect>& rects,
                          bool capture) {
  vk(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer");
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vk(vkBeginCommandBuffer(cmd_, &begin), "vkBeginCommandBuffer");
  VkClearValue clear;
  std::memcpy(clear.color.float32, background, sizeof(float) * 4);
  VkRenderPassBeginInfo rbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rbi.renderPass = pass_;
  rbi.framebuffer = framebuffers_[index];
  rbi.renderArea = {{0, 0}, extent_};
  rbi.clearValueCount = 1;
  rbi.pClearValues = &clear;
  vkCmdBeginRenderPass(cmd_, &rbi, VK_SUBPASS_CONTENTS_INLINE);
  for (const Rect& r : rects) {
    const int x0 = std::clamp(r.x, 0, width()), y0 = std::clamp(r.y, 0, height());
    const int x1 = std::clamp(r.x + r.w, 0, width()), y1 = std::clamp(r.y + r.h, 0, height());
    if (x1 <= x0 || y1 <= y0) continue;
    VkClearAttachment a{VK_IMAGE_ASPECT_COLOR_BIT, 0, {}};
    std::memcpy(a.clearValue.color.float32, r.rgba, sizeof(float) * 4);
    VkClearRect cr{{{x0, y0}, {uint32_t(x1 - x0), uint32_t(y1 - y0)}}, 0, 1};
    vkCmdClearAttachments(cmd_, 1, &a, 1, &cr);
  }
  vkCmdEndRenderPass(cmd_);
  if (capture) {
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {extent_.width, extent_.height, 1};
    vkCmdCopyImageToBuffer(cmd_, images_[index], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_, 1,
                           &copy);
  }
  VkImageMemoryBarrier to_present{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  to_present.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  to_present.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  to_present.newLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
  to_present.srcQueueFamilyIndex = to_present.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  to_present.image = images_[index];
  to_present.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(
      cmd_, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
      VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0, nullptr, 0, nullptr, 1, &to_present);
  vk(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer");
}

void VulkanWindow::submit_and_present(uint32_t index) {
  const VkPipelineStageFlags wait = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.waitSemaphoreCount = 1;
  submit.pWaitSemaphores = &acquired_;
  submit.pWaitDstStageMask = &wait;
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd_;
  submit.signalSemaphoreCount = 1;
  submit.pSignalSemaphores = &rendered_;
  VkPresentInfoKHR present{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  present.waitSemaphoreCount = 1;
  present.pWaitSemaphores = &rendered_;
  present.swapchainCount = 1;
  present.pSwapchains = &swapchain_;
  present.pImageIndices = &index;
  {
    std::lock_guard<std::mutex> lock(queue_lock);  // the audio runtime submits on this queue too
    vk(vkQueueSubmit(queue, 1, &submit, done_), "vkQueueSubmit");
    vk(vkQueuePresentKHR(queue, &present), "vkQueuePresentKHR");
  }
  vk(vkWaitForFences(device, 1, &done_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
  vk(vkResetFences(device, 1, &done_), "vkResetFences");
}

void VulkanWindow::read_back() {
  void* p = nullptr;
  vk(vkMapMemory(device, readback_memory_, 0, VK_WHOLE_SIZE, 0, &p), "vkMapMemory");
  const auto* px = static_cast<const uint8_t*>(p);
  const bool bgr = format_ == VK_FORMAT_B8G8R8A8_UNORM;
  captured.resize(std::size_t(width()) * height() * 3);
  for (std::size_t i = 0; i < std::size_t(width()) * height(); ++i)
    for (int c = 0; c < 3; ++c) captured[3 * i + c] = px[4 * i + (bgr ? 2 - c : c)];
  vkUnmapMemory(device, readback_memory_);
}

VulkanWindow::~VulkanWindow() {
  if (device) {
    vkDeviceWaitIdle(device);
    vkDestroyBuffer(device, readback_, nullptr);
    vkFreeMemory(device, readback_memory_, nullptr);
    vkDestroyFence(device, done_, nullptr);
    vkDestroySemaphore(device, rendered_, nullptr);
    vkDestroySemaphore(device, acquired_, nullptr);
    vkDestroyCommandPool(device, pool_, nullptr);
    for (VkFramebuffer f : framebuffers_) vkDestroyFramebuffer(device, f, nullptr);
    for (VkImageView v : views_) vkDestroyImageView(device, v, nullptr);
    vkDestroyRenderPass(device, pass_, nullptr);
    vkDestroySwapchainKHR(device, swapchain_, nullptr);
    vkDestroyDevice(device, nullptr);
  }
  if (instance) {
    if (surface_) vkDestroySurfaceKHR(instance, surface_, nullptr);
    vkDestroyInstance(instance, nullptr);
  }
  if (window_) SDL_DestroyWindow(window_);
}
