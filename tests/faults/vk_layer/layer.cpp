// A Vulkan layer for fault-injection tests: it sits between curvlab and the
// driver (lavapipe) and makes one call fail the way a lost or exhausted GPU
// does, so the renderer's and the backends' real error paths run — in
// process or in the real `curvlab` program, which has no switch for it.
//
// Enabled through the loader's environment (tests set it; never installed):
//   VK_LAYER_PATH=<build>/tests/faults/vk_layer
//   VK_INSTANCE_LAYERS=VK_LAYER_CURVLAB_test_faults
//   CURVLAB_TEST_VK_FAULT=CALL@N[:RESULT]
// CALL is vkQueueSubmit or vkWaitForFences; the N-th call of it (counted
// from vkCreateDevice, 1-based) returns RESULT (default
// VK_ERROR_DEVICE_LOST; also VK_ERROR_OUT_OF_DEVICE_MEMORY). A failing
// vkQueueSubmit submits nothing; a failing vkWaitForFences still waits, so
// the real device stays consistent for the teardown that follows. A lost
// device stays lost (Vulkan specification, "Lost Device"): every later
// vkQueueSubmit fails, and every later wait (vkWaitForFences,
// vkDeviceWaitIdle, vkQueueWaitIdle) waits and then returns
// VK_ERROR_DEVICE_LOST. The script is read at each vkCreateDevice; each
// injection is reported on stderr ("curvlab test vulkan layer: …").
//
// One device at a time (the tests' case); not for concurrent devices.
#include <vulkan/vk_layer.h>
#include <vulkan/vulkan.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>

namespace {

struct Script {
  std::string call;  // empty: no fault
  long at = 0;
  VkResult result = VK_ERROR_DEVICE_LOST;
};

struct State {
  std::mutex mutex;
  PFN_vkGetInstanceProcAddr next_gipa = nullptr;
  PFN_vkGetDeviceProcAddr next_gdpa = nullptr;
  PFN_vkQueueSubmit next_submit = nullptr;
  PFN_vkWaitForFences next_wait = nullptr;
  PFN_vkDeviceWaitIdle next_device_idle = nullptr;
  PFN_vkQueueWaitIdle next_queue_idle = nullptr;
  Script script;
  long submits = 0;
  long waits = 0;
  bool lost = false;
};

State& state() {
  static State s;
  return s;
}

Script read_script() {
  Script s;
  const char* env = std::getenv("CURVLAB_TEST_VK_FAULT");
  if (env == nullptr || *env == '\0') return s;
  const std::string text(env);
  const auto at = text.find('@');
  if (at == std::string::npos) {
    std::fprintf(stderr, "curvlab test vulkan layer: CURVLAB_TEST_VK_FAULT='%s' is not CALL@N[:RESULT]\n", env);
    std::abort();
  }
  s.call = text.substr(0, at);
  const auto colon = text.find(':', at);
  s.at = std::strtol(text.substr(at + 1, colon - at - 1).c_str(), nullptr, 10);
  if (colon != std::string::npos) {
    const std::string r = text.substr(colon + 1);
    if (r == "VK_ERROR_OUT_OF_DEVICE_MEMORY") s.result = VK_ERROR_OUT_OF_DEVICE_MEMORY;
    else if (r != "VK_ERROR_DEVICE_LOST") {
      std::fprintf(stderr, "curvlab test vulkan layer: unknown result '%s'\n", r.c_str());
      std::abort();
    }
  }
  if ((s.call != "vkQueueSubmit" && s.call != "vkWaitForFences") || s.at < 1) {
    std::fprintf(stderr, "curvlab test vulkan layer: cannot fail '%s' at %ld\n", s.call.c_str(), s.at);
    std::abort();
  }
  return s;
}

const char* name_of(VkResult r) {
  return r == VK_ERROR_DEVICE_LOST ? "VK_ERROR_DEVICE_LOST" : "VK_ERROR_OUT_OF_DEVICE_MEMORY";
}

// Whether this call (the n-th of `call`) is the scripted one; a scripted
// device loss sticks.
bool inject(State& s, const char* call, long n) {
  if (s.script.call != call || n != s.script.at) return false;
  std::fprintf(stderr, "curvlab test vulkan layer: %s #%ld returns %s\n", call, n, name_of(s.script.result));
  if (s.script.result == VK_ERROR_DEVICE_LOST) s.lost = true;
  return true;
}

VKAPI_ATTR VkResult VKAPI_CALL QueueSubmit(VkQueue queue, uint32_t count, const VkSubmitInfo* submits,
                                           VkFence fence) {
  State& s = state();
  PFN_vkQueueSubmit next = nullptr;
  {
    const std::lock_guard lock(s.mutex);
    if (s.lost) return VK_ERROR_DEVICE_LOST;
    if (inject(s, "vkQueueSubmit", ++s.submits)) return s.script.result;
    next = s.next_submit;
  }
  return next(queue, count, submits, fence);
}

VKAPI_ATTR VkResult VKAPI_CALL WaitForFences(VkDevice device, uint32_t count, const VkFence* fences,
                                             VkBool32 all, uint64_t timeout) {
  State& s = state();
  const VkResult r = s.next_wait(device, count, fences, all, timeout);
  const std::lock_guard lock(s.mutex);
  if (s.lost) return VK_ERROR_DEVICE_LOST;
  if (inject(s, "vkWaitForFences", ++s.waits)) return s.script.result;
  return r;
}

VKAPI_ATTR VkResult VKAPI_CALL DeviceWaitIdle(VkDevice device) {
  State& s = state();
  const VkResult r = s.next_device_idle(device);
  const std::lock_guard lock(s.mutex);
  return s.lost ? VK_ERROR_DEVICE_LOST : r;
}

VKAPI_ATTR VkResult VKAPI_CALL QueueWaitIdle(VkQueue queue) {
  State& s = state();
  const VkResult r = s.next_queue_idle(queue);
  const std::lock_guard lock(s.mutex);
  return s.lost ? VK_ERROR_DEVICE_LOST : r;
}

template <class T>
const T* find_link(const void* next, VkStructureType type) {
  for (auto* p = static_cast<const VkBaseInStructure*>(next); p != nullptr; p = p->pNext) {
    const auto* info = reinterpret_cast<const T*>(p);
    if (p->sType == type && info->function == VK_LAYER_LINK_INFO) return info;
  }
  return nullptr;
}

VKAPI_ATTR VkResult VKAPI_CALL CreateInstance(const VkInstanceCreateInfo* ci, const VkAllocationCallbacks* alloc,
                                              VkInstance* out) {
  auto* link = const_cast<VkLayerInstanceCreateInfo*>(
      find_link<VkLayerInstanceCreateInfo>(ci->pNext, VK_STRUCTURE_TYPE_LOADER_INSTANCE_CREATE_INFO));
  if (link == nullptr) return VK_ERROR_INITIALIZATION_FAILED;
  const PFN_vkGetInstanceProcAddr next = link->u.pLayerInfo->pfnNextGetInstanceProcAddr;
  link->u.pLayerInfo = link->u.pLayerInfo->pNext;  // the next layer finds its own link
  const auto create = reinterpret_cast<PFN_vkCreateInstance>(next(VK_NULL_HANDLE, "vkCreateInstance"));
  const VkResult r = create(ci, alloc, out);
  if (r == VK_SUCCESS) {
    const std::lock_guard lock(state().mutex);
    state().next_gipa = next;
  }
  return r;
}

VKAPI_ATTR VkResult VKAPI_CALL CreateDevice(VkPhysicalDevice physical, const VkDeviceCreateInfo* ci,
                                            const VkAllocationCallbacks* alloc, VkDevice* out) {
  auto* link = const_cast<VkLayerDeviceCreateInfo*>(
      find_link<VkLayerDeviceCreateInfo>(ci->pNext, VK_STRUCTURE_TYPE_LOADER_DEVICE_CREATE_INFO));
  if (link == nullptr) return VK_ERROR_INITIALIZATION_FAILED;
  const PFN_vkGetInstanceProcAddr gipa = link->u.pLayerInfo->pfnNextGetInstanceProcAddr;
  const PFN_vkGetDeviceProcAddr gdpa = link->u.pLayerInfo->pfnNextGetDeviceProcAddr;
  link->u.pLayerInfo = link->u.pLayerInfo->pNext;
  const auto create = reinterpret_cast<PFN_vkCreateDevice>(gipa(VK_NULL_HANDLE, "vkCreateDevice"));
  const VkResult r = create(physical, ci, alloc, out);
  if (r != VK_SUCCESS) return r;
  State& s = state();
  const std::lock_guard lock(s.mutex);
  s.next_gdpa = gdpa;
  s.next_submit = reinterpret_cast<PFN_vkQueueSubmit>(gdpa(*out, "vkQueueSubmit"));
  s.next_wait = reinterpret_cast<PFN_vkWaitForFences>(gdpa(*out, "vkWaitForFences"));
  s.next_device_idle = reinterpret_cast<PFN_vkDeviceWaitIdle>(gdpa(*out, "vkDeviceWaitIdle"));
  s.next_queue_idle = reinterpret_cast<PFN_vkQueueWaitIdle>(gdpa(*out, "vkQueueWaitIdle"));
  s.script = read_script();
  s.submits = 0;
  s.waits = 0;
  s.lost = false;
  return VK_SUCCESS;
}

PFN_vkVoidFunction own_device_function(const char* name);

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL GetDeviceProcAddr(VkDevice device, const char* name) {
  if (PFN_vkVoidFunction f = own_device_function(name)) return f;
  const PFN_vkGetDeviceProcAddr next = state().next_gdpa;
  return next != nullptr ? next(device, name) : nullptr;
}

PFN_vkVoidFunction own_device_function(const char* name) {
  if (std::strcmp(name, "vkGetDeviceProcAddr") == 0) return reinterpret_cast<PFN_vkVoidFunction>(&GetDeviceProcAddr);
  if (std::strcmp(name, "vkQueueSubmit") == 0) return reinterpret_cast<PFN_vkVoidFunction>(&QueueSubmit);
  if (std::strcmp(name, "vkWaitForFences") == 0) return reinterpret_cast<PFN_vkVoidFunction>(&WaitForFences);
  if (std::strcmp(name, "vkDeviceWaitIdle") == 0) return reinterpret_cast<PFN_vkVoidFunction>(&DeviceWaitIdle);
  if (std::strcmp(name, "vkQueueWaitIdle") == 0) return reinterpret_cast<PFN_vkVoidFunction>(&QueueWaitIdle);
  return nullptr;
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL GetInstanceProcAddr(VkInstance instance, const char* name) {
  if (std::strcmp(name, "vkGetInstanceProcAddr") == 0)
    return reinterpret_cast<PFN_vkVoidFunction>(&GetInstanceProcAddr);
  if (std::strcmp(name, "vkCreateInstance") == 0) return reinterpret_cast<PFN_vkVoidFunction>(&CreateInstance);
  if (std::strcmp(name, "vkCreateDevice") == 0) return reinterpret_cast<PFN_vkVoidFunction>(&CreateDevice);
  if (PFN_vkVoidFunction f = own_device_function(name)) return f;
  const PFN_vkGetInstanceProcAddr next = state().next_gipa;
  return next != nullptr ? next(instance, name) : nullptr;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) VKAPI_ATTR VkResult VKAPI_CALL
vkNegotiateLoaderLayerInterfaceVersion(VkNegotiateLayerInterface* v) {
  if (v == nullptr || v->sType != LAYER_NEGOTIATE_INTERFACE_STRUCT) return VK_ERROR_INITIALIZATION_FAILED;
  if (v->loaderLayerInterfaceVersion > 2) v->loaderLayerInterfaceVersion = 2;
  v->pfnGetInstanceProcAddr = &GetInstanceProcAddr;
  v->pfnGetDeviceProcAddr = &GetDeviceProcAddr;
  v->pfnGetPhysicalDeviceProcAddr = nullptr;
  return VK_SUCCESS;
}
