// Environment for the fault-injection tests: the test Vulkan layer
// (vk_layer/layer.cpp) enabled with a scripted fault for as long as the
// object lives. The loader reads VK_INSTANCE_LAYERS when an instance is
// made and the layer reads its script when a device is made, so this works
// in process as well as for a program started meanwhile.
#pragma once

#include <cstdlib>
#include <string>

namespace curvlab::testing {

class VulkanFault {
 public:
  // `script`: CALL@N[:RESULT] (layer.cpp), e.g. "vkQueueSubmit@5".
  explicit VulkanFault(const std::string& script) {
    setenv("VK_LAYER_PATH", CURVLAB_TEST_VK_LAYER_DIR, 1);
    setenv("VK_INSTANCE_LAYERS", "VK_LAYER_CURVLAB_test_faults", 1);
    setenv("CURVLAB_TEST_VK_FAULT", script.c_str(), 1);
  }
  ~VulkanFault() {
    unsetenv("VK_LAYER_PATH");
    unsetenv("VK_INSTANCE_LAYERS");
    unsetenv("CURVLAB_TEST_VK_FAULT");
  }
  VulkanFault(const VulkanFault&) = delete;
  VulkanFault& operator=(const VulkanFault&) = delete;
};

}  // namespace curvlab::testing
