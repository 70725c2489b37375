// The GPU backend on an application's own Vulkan device: a renderer thread draws offscreen on
// its queue while the audio thread renders on the device's other queue (or, on a device with one
// queue such as lavapipe, on the same queue under the application's lock). The validation layer
// reports nothing and the audio is the CPU backend's.
#include <gtest/gtest.h>
#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "chladni/chladni.h"
#include "test_support.hpp"

namespace {

#define VK_OK(call) ASSERT_EQ((call), VK_SUCCESS) << #call

std::atomic<int> g_validation_errors{0};

VKAPI_ATTR VkBool32 VKAPI_CALL count_errors(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                            VkDebugUtilsMessageTypeFlagsEXT,
                                            const VkDebugUtilsMessengerCallbackDataEXT* data,
                                            void*) {
  if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
    ++g_validation_errors;
    ADD_FAILURE() << "validation: " << data->pMessage;
  }
  return VK_FALSE;
}

bool has_validation_layer() {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  for (const auto& l : layers)
    if (std::strcmp(l.layerName, "VK_LAYER_KHRONOS_validation") == 0) return true;
  return false;
}

// The application: an instance (with validation where installed), a device with a graphics
// queue and, where the family has two, a second queue for the runtime; an offscreen colour
// target it clears through a render pass and reads back.
struct App {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t family = 0, queues = 0;
  VkQueue graphics = VK_NULL_HANDLE;
  std::mutex queue_lock;  // held around submits when the runtime shares the graphics queue
  std::atomic<int> runtime_submits{0};
  VkImage image = VK_NULL_HANDLE;
  VkBuffer readback = VK_NULL_HANDLE;
  VkDeviceMemory image_memory = VK_NULL_HANDLE, readback_memory = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkRenderPass pass = VK_NULL_HANDLE;
  VkFramebuffer framebuffer = VK_NULL_HANDLE;
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  static constexpr uint32_t kSize = 16;

  ~App() {
    if (device) {
      vkDeviceWaitIdle(device);
      vkDestroyFence(device, fence, nullptr);
      vkDestroyCommandPool(device, pool, nullptr);
      vkDestroyFramebuffer(device, framebuffer, nullptr);
      vkDestroyRenderPass(device, pass, nullptr);
      vkDestroyImageView(device, view, nullptr);
      vkDestroyImage(device, image, nullptr);
      vkDestroyBuffer(device, readback, nullptr);
      vkFreeMemory(device, image_memory, nullptr);
      vkFreeMemory(device, readback_memory, nullptr);
      vkDestroyDevice(device, nullptr);
    }
    if (messenger) {
      auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
      destroy(instance, messenger, nullptr);
    }
    if (instance) vkDestroyInstance(instance, nullptr);
  }

  uint32_t memory_type(uint32_t bits, VkMemoryPropertyFlags want) const {
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(physical, &mp);
    for (uint32_t i = 0; i < mp.memoryTypeCount; ++i)
      if ((bits & (1u << i)) && (mp.memoryTypes[i].propertyFlags & want) == want) return i;
    return 0;
  }
};

// Instance, device and queues; false (nothing to test on) without a graphics+compute family.
bool open(App& a, bool validation) {
  VkApplicationInfo info{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  info.apiVersion = VK_API_VERSION_1_1;
  VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ci.pApplicationInfo = &info;
  const char* layer = "VK_LAYER_KHRONOS_validation";
  const char* ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
  if (validation) {
    ci.enabledLayerCount = 1;
    ci.ppEnabledLayerNames = &layer;
    ci.enabledExtensionCount = 1;
    ci.ppEnabledExtensionNames = &ext;
  }
  if (vkCreateInstance(&ci, nullptr, &a.instance) != VK_SUCCESS) return false;
  if (validation) {
    VkDebugUtilsMessengerCreateInfoEXT mi{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    mi.pfnUserCallback = &count_errors;
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(a.instance, "vkCreateDebugUtilsMessengerEXT"));
    if (create) create(a.instance, &mi, nullptr, &a.messenger);
  }
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(a.instance, &n, nullptr);
  std::vector<VkPhysicalDevice> pds(n);
  vkEnumeratePhysicalDevices(a.instance, &n, pds.data());
  for (VkPhysicalDevice pd : pds) {
    uint32_t nf = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &nf, nullptr);
    std::vector<VkQueueFamilyProperties> fams(nf);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &nf, fams.data());
    for (uint32_t f = 0; f < nf && !a.physical; ++f)
      if ((fams[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
          (fams[f].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
        a.physical = pd;
        a.family = f;
        a.queues = std::min(2u, fams[f].queueCount);
      }
  }
  if (!a.physical) return false;
  const float priorities[2] = {1.0f, 1.0f};
  VkDeviceQueueCreateInfo qi{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qi.queueFamilyIndex = a.family;
  qi.queueCount = a.queues;
  qi.pQueuePriorities = priorities;
  VkDeviceCreateInfo di{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  di.queueCreateInfoCount = 1;
  di.pQueueCreateInfos = &qi;
  if (vkCreateDevice(a.physical, &di, nullptr, &a.device) != VK_SUCCESS) return false;
  vkGetDeviceQueue(a.device, a.family, 0, &a.graphics);
  return true;
}

// The offscreen target: an image cleared by a render pass, copied to a host-visible buffer.
void make_target(App& a) {
  VkImageCreateInfo ii{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ii.imageType = VK_IMAGE_TYPE_2D;
  ii.format = VK_FORMAT_R8G8B8A8_UNORM;
  ii.extent = {App::kSize, App::kSize, 1};
  ii.mipLevels = ii.arrayLayers = 1;
  ii.samples = VK_SAMPLE_COUNT_1_BIT;
  ii.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  VK_OK(vkCreateImage(a.device, &ii, nullptr, &a.image));
  VkMemoryRequirements mr;
  vkGetImageMemoryRequirements(a.device, a.image, &mr);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = mr.size;
  ai.memoryTypeIndex = a.memory_type(mr.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  VK_OK(vkAllocateMemory(a.device, &ai, nullptr, &a.image_memory));
  VK_OK(vkBindImageMemory(a.device, a.image, a.image_memory, 0));
  VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bi.size = 4 * App::kSize * App::kSize;
  bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VK_OK(vkCreateBuffer(a.device, &bi, nullptr, &a.readback));
  vkGetBufferMemoryRequirements(a.device, a.readback, &mr);
  ai.allocationSize = mr.size;
  ai.memoryTypeIndex = a.memory_type(mr.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                                            VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
  VK_OK(vkAllocateMemory(a.device, &ai, nullptr, &a.readback_memory));
  VK_OK(vkBindBufferMemory(a.device, a.readback, a.readback_memory, 0));
  VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vi.image = a.image;
  vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vi.format = ii.format;
  vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  VK_OK(vkCreateImageView(a.device, &vi, nullptr, &a.view));
  VkAttachmentDescription at{};
  at.format = ii.format;
  at.samples = VK_SAMPLE_COUNT_1_BIT;
  at.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  at.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  at.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  at.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  at.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  at.finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription sub{};
  sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  sub.colorAttachmentCount = 1;
  sub.pColorAttachments = &ref;
  // The copy after the pass reads what the clear wrote.
  VkSubpassDependency dep{};
  dep.srcSubpass = 0;
  dep.dstSubpass = VK_SUBPASS_EXTERNAL;
  dep.srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  dep.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  dep.dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
  dep.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  VkRenderPassCreateInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rp.attachmentCount = 1;
  rp.pAttachments = &at;
  rp.subpassCount = 1;
  rp.pSubpasses = &sub;
  rp.dependencyCount = 1;
  rp.pDependencies = &dep;
  VK_OK(vkCreateRenderPass(a.device, &rp, nullptr, &a.pass));
  VkFramebufferCreateInfo fi{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
  fi.renderPass = a.pass;
  fi.attachmentCount = 1;
  fi.pAttachments = &a.view;
  fi.width = fi.height = App::kSize;
  fi.layers = 1;
  VK_OK(vkCreateFramebuffer(a.device, &fi, nullptr, &a.framebuffer));
  VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pi.queueFamilyIndex = a.family;
  VK_OK(vkCreateCommandPool(a.device, &pi, nullptr, &a.pool));
  VkCommandBufferAllocateInfo cb{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cb.commandPool = a.pool;
  cb.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cb.commandBufferCount = 1;
  VK_OK(vkAllocateCommandBuffers(a.device, &cb, &a.cmd));
  VkFenceCreateInfo fc{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VK_OK(vkCreateFence(a.device, &fc, nullptr, &a.fence));
}

// One frame: clears the target to grey level `g` and reads back its first pixel's red byte.
int draw(App& a, uint8_t g) {
  vkResetCommandBuffer(a.cmd, 0);
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  vkBeginCommandBuffer(a.cmd, &bi);
  VkClearValue clear{};
  clear.color.float32[0] = clear.color.float32[1] = clear.color.float32[2] = g / 255.0f;
  clear.color.float32[3] = 1.0f;
  VkRenderPassBeginInfo rb{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rb.renderPass = a.pass;
  rb.framebuffer = a.framebuffer;
  rb.renderArea.extent = {App::kSize, App::kSize};
  rb.clearValueCount = 1;
  rb.pClearValues = &clear;
  vkCmdBeginRenderPass(a.cmd, &rb, VK_SUBPASS_CONTENTS_INLINE);
  vkCmdEndRenderPass(a.cmd);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {App::kSize, App::kSize, 1};
  vkCmdCopyImageToBuffer(a.cmd, a.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, a.readback, 1,
                         &region);
  vkEndCommandBuffer(a.cmd);
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &a.cmd;
  {
    std::lock_guard<std::mutex> hold(a.queue_lock);
    if (vkQueueSubmit(a.graphics, 1, &si, a.fence) != VK_SUCCESS) return -1;
  }
  vkWaitForFences(a.device, 1, &a.fence, VK_TRUE, UINT64_MAX);
  vkResetFences(a.device, 1, &a.fence);
  void* p = nullptr;
  vkMapMemory(a.device, a.readback_memory, 0, VK_WHOLE_SIZE, 0, &p);
  const int red = static_cast<const uint8_t*>(p)[0];
  vkUnmapMemory(a.device, a.readback_memory);
  return red;
}

// Two struck modes and a listener step, rendered in blocks of 256 by one backend.
std::vector<float> play(chladni_backend backend, const chladni_vulkan_device* vulkan) {
  chladni_config c;
  chladni_config_default(&c);
  c.backend = backend;
  c.threads = 1;
  c.mode_budget = 4096;
  c.gpu_pipeline = 0;
  c.vulkan = vulkan;
  chladni_runtime* rt = nullptr;
  EXPECT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_OK) << chladni_last_error();
  if (!rt) return {};
  const double hz[] = {441, 1142, 2650}, decay[] = {2, 3, 5}, amp[] = {0.02, 0.01, 0.004};
  chladni_bank bank{0};
  EXPECT_EQ(chladni_bank_from_modes(rt, hz, decay, amp, 3, &bank), CHLADNI_OK);
  const double at[3] = {0.3, 1, 0}, q[4] = {1, 0, 0, 0}, fwd[3] = {0, 1, 0}, up[3] = {0, 0, 1},
               near[3] = {0.1, 0.5, 0};
  chladni_object o{0};
  EXPECT_EQ(chladni_object_spawn(rt, bank, at, q, 1.0, &o), CHLADNI_OK);
  for (int k = 0; k < 5; ++k) {
    chladni_impact im{};
    im.object = o;
    im.time = 0.011 + 0.07 * k;
    im.impulse = 0.01;
    im.direction[2] = -1;
    im.vertex = -1;
    im.contact_time = k % 2 ? 0.001 : 0.0;
    EXPECT_EQ(chladni_impact_post(rt, &im), CHLADNI_OK);
  }
  EXPECT_EQ(chladni_listener_set(rt, 0.2, near, fwd, up), CHLADNI_OK);
  std::vector<float> out(2 * 256 * 120);
  for (int b = 0; b < 120; ++b)
    EXPECT_EQ(chladni_runtime_render(rt, out.data() + 2 * 256 * b, 256), CHLADNI_OK)
        << chladni_last_error();
  chladni_runtime_destroy(rt);
  return out;
}

}  // namespace

TEST(SharedDevice, RendersAudioBesideTheApplicationsDrawingOnItsOwnDevice) {
  App app;
  const bool validation = has_validation_layer();
  if (!open(app, validation)) {
    if (std::getenv("CHLADNI_REQUIRE_GPU")) FAIL() << "no Vulkan device with a graphics queue";
    GTEST_SKIP() << "no Vulkan device with a graphics queue";
  }
  make_target(app);
  ASSERT_EQ(draw(app, 200), 200);
  // The runtime's queue: the second where the family has two, else the graphics queue itself,
  // under the application's lock.
  chladni_vulkan_device shared{};
  shared.instance = app.instance;
  shared.physical_device = app.physical;
  shared.device = app.device;
  shared.queue_family = app.family;
  shared.queue_index = app.queues > 1 ? 1 : 0;
  shared.get_instance_proc_addr = reinterpret_cast<void*>(&vkGetInstanceProcAddr);
  if (app.queues == 1) {
    shared.lock_queue = [](void* u) {
      static_cast<App*>(u)->queue_lock.lock();
      ++static_cast<App*>(u)->runtime_submits;
    };
    shared.unlock_queue = [](void* u) { static_cast<App*>(u)->queue_lock.unlock(); };
    shared.user = &app;
  }
  std::atomic<bool> audio_done{false};
  std::atomic<int> frames{0}, wrong{0};
  std::thread renderer([&] {
    for (int f = 0; !audio_done.load() || f < 3; ++f) {
      const uint8_t g = static_cast<uint8_t>(40 + (f * 37) % 200);
      if (draw(app, g) != g) ++wrong;
      ++frames;
    }
  });
  const std::vector<float> gpu = play(CHLADNI_BACKEND_GPU, &shared);
  audio_done.store(true);
  renderer.join();
  const std::vector<float> cpu = play(CHLADNI_BACKEND_CPU, nullptr);
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_GE(frames.load(), 3);
  // On one queue, every block went through the application's lock: the runtime submitted on the
  // application's device and queue, not on a device of its own.
  if (app.queues == 1) {
    EXPECT_GE(app.runtime_submits.load(), 120);
  }
  ASSERT_EQ(gpu.size(), cpu.size());
  const double peak = chladni::test::max_abs(cpu);
  ASSERT_GT(peak, 1e-4);
  EXPECT_LT(chladni::test::max_diff(cpu, gpu), 1e-4 * peak);
  EXPECT_EQ(g_validation_errors.load(), 0);
  // A queue the family does not have, or half a lock, is refused with its reason.
  chladni_vulkan_device bad = shared;
  bad.queue_index = 7;
  chladni_config c;
  chladni_config_default(&c);
  c.backend = CHLADNI_BACKEND_GPU;
  c.vulkan = &bad;
  chladni_runtime* rt = nullptr;
  EXPECT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("not index 7"), std::string::npos)
      << chladni_last_error();
  bad = shared;
  bad.lock_queue = [](void*) {};
  bad.unlock_queue = nullptr;
  EXPECT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_INPUT_ERROR);
  EXPECT_NE(std::string(chladni_last_error()).find("go together"), std::string::npos);
}
