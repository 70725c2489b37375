#pragma once
// Vulkan instance, physical-device choice and logical device for compute. No sound knowledge.
#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace chladni::gpu {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// No usable Vulkan device (no loader, no driver, or the selection matched nothing). Callers
/// turn this into a CPU fallback with one warning.
class NoDeviceError : public Error {
 public:
  using Error::Error;
};

/// Throws Error naming the call and the VkResult when r is not VK_SUCCESS.
void check(VkResult r, const char* what);
const char* result_name(VkResult r);

struct DeviceInfo {
  uint32_t index = 0;
  std::string name;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  uint32_t api_version = 0;
  std::string type_name() const;
};

struct ContextOptions {
  /// Index or case-insensitive name substring; empty: $CHLADNI_VULKAN_DEVICE, else the best device
  /// (discrete > integrated > virtual > CPU).
  std::string device;
  /// Enable VK_LAYER_KHRONOS_validation if installed. Default: on in debug builds.
  bool validation = default_validation();
  static bool default_validation();
};

/// A device the application made (a renderer's), for the runtime to share: it then creates no
/// instance or device, records on the given queue, and leaves the handles' ownership to the
/// application, which keeps them alive while the Context lives. The runtime calls Vulkan through
/// the system loader (libvulkan.so.1), so the handles must come from it.
struct ExternalDevice {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t queue_family = 0;  ///< must support compute
  uint32_t queue_index = 0;
  /// The loader's vkGetInstanceProcAddr the handles were made with (optional): the device's
  /// functions must resolve through it.
  PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;
  /// Called around each submit when the queue is shared with the application's threads (a
  /// queue must not be submitted to from two threads at once); both or neither.
  std::function<void()> lock_queue, unlock_queue;
};

class Context {
 public:
  explicit Context(const ContextOptions& options = {});
  /// Shares an application's device; throws Error naming what does not fit.
  explicit Context(const ExternalDevice& device);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  /// Lists the Vulkan devices with compute support (throws NoDeviceError without a loader).
  static std::vector<DeviceInfo> list_devices();

  VkDevice device() const { return device_; }
  VkPhysicalDevice physical_device() const { return physical_; }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  VkCommandPool command_pool() const { return pool_; }
  const DeviceInfo& info() const { return info_; }
  const VkPhysicalDeviceLimits& limits() const { return properties_.limits; }

  uint32_t subgroup_size() const { return subgroup_size_; }
  bool subgroup_arithmetic() const { return subgroup_arithmetic_; }
  bool timestamps() const { return timestamps_; }
  double timestamp_period_ns() const { return properties_.limits.timestampPeriod; }
  uint64_t timestamp_mask() const { return timestamp_mask_; }

  /// A memory type index with all `required` flags, preferring one with `preferred` too.
  uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                       VkMemoryPropertyFlags preferred, VkMemoryPropertyFlags* got = nullptr) const;

  /// Submits to the queue, under the application's lock when it shares the queue.
  void submit(const VkSubmitInfo& info, VkFence fence);
  /// False for an application's device (ExternalDevice).
  bool owns_device() const { return owned_; }

  bool validation_enabled() const { return messenger_ != VK_NULL_HANDLE; }
  /// Validation-layer errors reported so far (tests require zero).
  std::size_t validation_errors() const { return validation_errors_.load(); }
  std::string describe() const;

 private:
  void release();
  void inspect_device();
  void create_pool();
  static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                   VkDebugUtilsMessageTypeFlagsEXT,
                                                   const VkDebugUtilsMessengerCallbackDataEXT*,
                                                   void*);
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  DeviceInfo info_;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  uint32_t subgroup_size_ = 1;
  bool subgroup_arithmetic_ = false;
  bool timestamps_ = false;
  uint64_t timestamp_mask_ = 0;
  std::atomic<std::size_t> validation_errors_{0};
  bool owned_ = true;
  std::function<void()> lock_queue_, unlock_queue_;
};

/// Where work that can run on either side should go.
enum class DeviceChoice {
  Cpu,   ///< no device
  Gpu,   ///< the chosen Vulkan device, whatever its type
  Auto,  ///< a discrete or integrated GPU; a CPU driver such as lavapipe is slower than the CPU
};

/// A discrete or integrated GPU, not a CPU driver or a virtual device.
bool is_hardware_gpu(const DeviceInfo& info);

/// The device for `choice`: null for Cpu, and for Auto without a hardware GPU. Gpu without a usable
/// device calls `on_missing` with the reason (when given) and returns null.
std::shared_ptr<Context> open_device(
    DeviceChoice choice, const std::function<void(const std::string&)>& on_missing = {});

}  // namespace chladni::gpu
