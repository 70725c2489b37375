#include "chladni/gpu/context.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

namespace chladni::gpu {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

int type_rank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return 3;
    default:
      return 4;
  }
}

bool has_layer(const char* name) {
  uint32_t n = 0;
  if (vkEnumerateInstanceLayerProperties(&n, nullptr) != VK_SUCCESS) return false;
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  return std::any_of(layers.begin(), layers.end(), [&](const VkLayerProperties& l) {
    return std::strcmp(l.layerName, name) == 0;
  });
}

bool has_instance_extension(const char* name) {
  uint32_t n = 0;
  if (vkEnumerateInstanceExtensionProperties(nullptr, &n, nullptr) != VK_SUCCESS) return false;
  std::vector<VkExtensionProperties> ext(n);
  vkEnumerateInstanceExtensionProperties(nullptr, &n, ext.data());
  return std::any_of(ext.begin(), ext.end(), [&](const VkExtensionProperties& e) {
    return std::strcmp(e.extensionName, name) == 0;
  });
}

VkInstance create_instance(bool validation, bool* validation_on) {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "chladni";
  app.pEngineName = "chladni";
  app.apiVersion = VK_API_VERSION_1_1;
  std::vector<const char*> layers, extensions;
  *validation_on = validation && has_layer(kValidationLayer) &&
                   has_instance_extension(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  if (*validation_on) {
    layers.push_back(kValidationLayer);
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ci.pApplicationInfo = &app;
  ci.enabledLayerCount = static_cast<uint32_t>(layers.size());
  ci.ppEnabledLayerNames = layers.data();
  ci.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  ci.ppEnabledExtensionNames = extensions.data();
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = vkCreateInstance(&ci, nullptr, &instance);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER || r == VK_ERROR_INITIALIZATION_FAILED ||
      r == VK_ERROR_LAYER_NOT_PRESENT || r == VK_ERROR_EXTENSION_NOT_PRESENT) {
    throw NoDeviceError(std::string("no Vulkan driver available (vkCreateInstance: ") +
                        result_name(r) + ")");
  }
  check(r, "vkCreateInstance");
  return instance;
}

int compute_family(VkPhysicalDevice pd) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fams(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
  // Prefer a compute queue that is not also graphics (async compute on real GPUs).
  int best = -1;
  for (uint32_t i = 0; i < n; ++i) {
    if (!(fams[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) continue;
    if (best < 0 || !(fams[i].queueFlags & VK_QUEUE_GRAPHICS_BIT)) best = static_cast<int>(i);
  }
  return best;
}

struct Candidate {
  VkPhysicalDevice pd;
  DeviceInfo info;
};

std::vector<Candidate> candidates(VkInstance instance) {
  uint32_t n = 0;
  check(vkEnumeratePhysicalDevices(instance, &n, nullptr), "vkEnumeratePhysicalDevices");
  std::vector<VkPhysicalDevice> pds(n);
  check(vkEnumeratePhysicalDevices(instance, &n, pds.data()), "vkEnumeratePhysicalDevices");
  std::vector<Candidate> out;
  for (uint32_t i = 0; i < n; ++i) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pds[i], &p);
    if (p.apiVersion < VK_API_VERSION_1_1 || compute_family(pds[i]) < 0) continue;
    out.push_back({pds[i], DeviceInfo{i, p.deviceName, p.deviceType, p.apiVersion}});
  }
  return out;
}

// The device named by `selector` (or CHLADNI_VULKAN_DEVICE): an index or part of a name;
// without one, the most capable type (discrete before integrated before CPU).
const Candidate* choose_device(const std::vector<Candidate>& cands, std::string selector) {
  if (selector.empty())
    if (const char* env = std::getenv("CHLADNI_VULKAN_DEVICE")) selector = env;
  if (selector.empty())
    return &*std::min_element(cands.begin(), cands.end(), [](const auto& a, const auto& b) {
      return type_rank(a.info.type) < type_rank(b.info.type);
    });
  const bool numeric = std::all_of(selector.begin(), selector.end(),
                                   [](unsigned char c) { return std::isdigit(c); });
  for (const Candidate& c : cands)
    if (numeric ? c.info.index == std::stoul(selector)
                : lower(c.info.name).find(lower(selector)) != std::string::npos)
      return &c;
  std::ostringstream os;
  os << "no Vulkan device matches '" << selector << "' (CHLADNI_VULKAN_DEVICE); devices:";
  for (const Candidate& c : cands) os << " [" << c.info.index << "] " << c.info.name << ";";
  throw NoDeviceError(os.str());
}

}  // namespace

const char* result_name(VkResult r) {
  switch (r) {
#define CHLADNI_CASE(x) \
  case x:               \
    return #x;
    CHLADNI_CASE(VK_SUCCESS)
    CHLADNI_CASE(VK_NOT_READY)
    CHLADNI_CASE(VK_TIMEOUT)
    CHLADNI_CASE(VK_INCOMPLETE)
    CHLADNI_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
    CHLADNI_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    CHLADNI_CASE(VK_ERROR_INITIALIZATION_FAILED)
    CHLADNI_CASE(VK_ERROR_DEVICE_LOST)
    CHLADNI_CASE(VK_ERROR_MEMORY_MAP_FAILED)
    CHLADNI_CASE(VK_ERROR_LAYER_NOT_PRESENT)
    CHLADNI_CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
    CHLADNI_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
    CHLADNI_CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
    CHLADNI_CASE(VK_ERROR_TOO_MANY_OBJECTS)
    CHLADNI_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
    CHLADNI_CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
#undef CHLADNI_CASE
    default:
      return "VkResult(unknown)";
  }
}

void check(VkResult r, const char* what) {
  if (r == VK_SUCCESS) return;
  std::ostringstream os;
  os << what << " failed: " << result_name(r) << " (" << static_cast<int>(r) << ")";
  throw Error(os.str());
}

std::string DeviceInfo::type_name() const {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return "CPU";
    default:
      return "other";
  }
}

bool is_hardware_gpu(const DeviceInfo& info) {
  return info.type == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU ||
         info.type == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU;
}

std::shared_ptr<Context> open_device(DeviceChoice choice,
                                     const std::function<void(const std::string&)>& on_missing) {
  if (choice == DeviceChoice::Cpu) return nullptr;
  try {
    auto ctx = std::make_shared<Context>();
    if (choice == DeviceChoice::Auto && !is_hardware_gpu(ctx->info())) return nullptr;
    return ctx;
  } catch (const NoDeviceError& e) {
    if (choice == DeviceChoice::Gpu && on_missing) on_missing(e.what());
    return nullptr;
  }
}

bool ContextOptions::default_validation() {
#ifdef CHLADNI_VULKAN_VALIDATION_DEFAULT
  return true;
#else
  return false;
#endif
}

std::vector<DeviceInfo> Context::list_devices() {
  bool unused = false;
  VkInstance instance = create_instance(false, &unused);
  std::vector<DeviceInfo> out;
  try {
    for (const Candidate& c : candidates(instance)) out.push_back(c.info);
  } catch (...) {
    vkDestroyInstance(instance, nullptr);
    throw;
  }
  vkDestroyInstance(instance, nullptr);
  return out;
}

VKAPI_ATTR VkBool32 VKAPI_CALL Context::on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                   VkDebugUtilsMessageTypeFlagsEXT,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                   void* user) {
  auto* self = static_cast<Context*>(user);
  if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
    ++self->validation_errors_;
    std::fprintf(stderr, "vulkan validation error: %s\n", data->pMessage);
  } else if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    std::fprintf(stderr, "vulkan validation warning: %s\n", data->pMessage);
  }
  return VK_FALSE;
}

Context::Context(const ContextOptions& options) {
  bool validation_on = false;
  instance_ = create_instance(options.validation, &validation_on);
  try {
    if (validation_on) {
      VkDebugUtilsMessengerCreateInfoEXT mi{
          VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
      mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
      mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
      mi.pfnUserCallback = &Context::on_message;
      mi.pUserData = this;
      auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
      if (create)
        check(create(instance_, &mi, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
    }

    std::vector<Candidate> cands = candidates(instance_);
    if (cands.empty()) throw NoDeviceError("no Vulkan 1.1 device with a compute queue found");
    const Candidate* chosen = choose_device(cands, options.device);
    physical_ = chosen->pd;
    info_ = chosen->info;
    queue_family_ = static_cast<uint32_t>(compute_family(physical_));
    inspect_device();

    const float priority = 1.0f;
    VkDeviceQueueCreateInfo qi{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qi.queueFamilyIndex = queue_family_;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    VkDeviceCreateInfo di{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    check(vkCreateDevice(physical_, &di, nullptr, &device_), "vkCreateDevice");
    vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
    create_pool();
  } catch (...) {
    release();
    throw;
  }
}

Context::Context(const ExternalDevice& d) : owned_(false) {
  if (!d.instance || !d.physical || !d.device)
    throw Error("a shared Vulkan device needs its instance, physical device and device");
  if (bool(d.lock_queue) != bool(d.unlock_queue))
    throw Error("lock_queue and unlock_queue go together: give both or neither");
  if (d.get_instance_proc_addr && !d.get_instance_proc_addr(d.instance, "vkGetDeviceProcAddr"))
    throw Error("the shared device's vkGetInstanceProcAddr does not resolve its functions");
  physical_ = d.physical;
  device_ = d.device;
  queue_family_ = d.queue_family;
  uint32_t nf = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &nf, nullptr);
  std::vector<VkQueueFamilyProperties> fams(nf);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &nf, fams.data());
  if (queue_family_ >= nf || !(fams[queue_family_].queueFlags & VK_QUEUE_COMPUTE_BIT))
    throw Error("queue family " + std::to_string(queue_family_) + " has no compute queue");
  if (d.queue_index >= fams[queue_family_].queueCount)
    throw Error("queue family " + std::to_string(queue_family_) + " has " +
                std::to_string(fams[queue_family_].queueCount) + " queues, not index " +
                std::to_string(d.queue_index));
  vkGetPhysicalDeviceProperties(physical_, &properties_);
  if (properties_.apiVersion < VK_API_VERSION_1_1)
    throw Error("the shared device is not Vulkan 1.1");
  info_.name = properties_.deviceName;
  info_.type = properties_.deviceType;
  info_.api_version = properties_.apiVersion;
  inspect_device();
  vkGetDeviceQueue(device_, queue_family_, d.queue_index, &queue_);
  lock_queue_ = d.lock_queue;
  unlock_queue_ = d.unlock_queue;
  try {
    create_pool();
  } catch (...) {
    release();
    throw;
  }
}

// Limits, memory types, subgroups and timestamps of physical_ and queue_family_.
void Context::inspect_device() {
  vkGetPhysicalDeviceProperties(physical_, &properties_);
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);
  VkPhysicalDeviceSubgroupProperties sub{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  p2.pNext = &sub;
  vkGetPhysicalDeviceProperties2(physical_, &p2);
  subgroup_size_ = std::max(1u, sub.subgroupSize);
  subgroup_arithmetic_ = (sub.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) &&
                         (sub.supportedOperations & VK_SUBGROUP_FEATURE_ARITHMETIC_BIT);
  uint32_t nf = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &nf, nullptr);
  std::vector<VkQueueFamilyProperties> fams(nf);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &nf, fams.data());
  const uint32_t bits = fams[queue_family_].timestampValidBits;
  timestamps_ = bits > 0 && properties_.limits.timestampPeriod > 0;
  timestamp_mask_ = bits >= 64 ? ~uint64_t{0} : ((uint64_t{1} << bits) - 1);
}

void Context::create_pool() {
  VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pi.queueFamilyIndex = queue_family_;
  check(vkCreateCommandPool(device_, &pi, nullptr, &pool_), "vkCreateCommandPool");
}

void Context::submit(const VkSubmitInfo& info, VkFence fence) {
  if (!lock_queue_) {
    check(vkQueueSubmit(queue_, 1, &info, fence), "vkQueueSubmit");
    return;
  }
  lock_queue_();
  const VkResult r = vkQueueSubmit(queue_, 1, &info, fence);
  unlock_queue_();
  check(r, "vkQueueSubmit");
}

Context::~Context() {
  release();
}

void Context::release() {
  if (device_ && !owned_) {  // the application's: only what was made here goes
    if (pool_) vkDestroyCommandPool(device_, pool_, nullptr);
    device_ = VK_NULL_HANDLE;
    pool_ = VK_NULL_HANDLE;
    return;
  }
  if (device_) {
    vkDeviceWaitIdle(device_);
    if (pool_) vkDestroyCommandPool(device_, pool_, nullptr);
    vkDestroyDevice(device_, nullptr);
    device_ = VK_NULL_HANDLE;
    pool_ = VK_NULL_HANDLE;
  }
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
    messenger_ = VK_NULL_HANDLE;
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
  instance_ = VK_NULL_HANDLE;
}

uint32_t Context::memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                              VkMemoryPropertyFlags preferred, VkMemoryPropertyFlags* got) const {
  int fallback = -1;
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
    if (!(type_bits & (1u << i))) continue;
    const VkMemoryPropertyFlags f = memory_.memoryTypes[i].propertyFlags;
    if ((f & required) != required) continue;
    if ((f & preferred) == preferred) {
      if (got) *got = f;
      return i;
    }
    if (fallback < 0) fallback = static_cast<int>(i);
  }
  if (fallback < 0) throw Error("no Vulkan memory type with the required properties");
  if (got) *got = memory_.memoryTypes[fallback].propertyFlags;
  return static_cast<uint32_t>(fallback);
}

std::string Context::describe() const {
  std::ostringstream os;
  os << info_.name << " (" << info_.type_name() << ", Vulkan "
     << VK_API_VERSION_MAJOR(info_.api_version) << "." << VK_API_VERSION_MINOR(info_.api_version)
     << ", subgroup " << subgroup_size_ << ")";
  return os.str();
}

}  // namespace chladni::gpu
