#include "curvlab/harness/xr/stereo.hpp"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>

namespace curvlab::harness::xr {
namespace {

// VkFormat numbers (vulkan_core.h), kept here so this file needs no Vulkan
// header; a test checks them against the header.
constexpr std::int64_t kR8G8B8A8Unorm = 37;
constexpr std::int64_t kR8G8B8A8Srgb = 43;
constexpr std::int64_t kB8G8R8A8Unorm = 44;
constexpr std::int64_t kB8G8R8A8Srgb = 50;

}  // namespace

renderer::StereoRig rig_from_views(const StagePose& head, const std::array<StagePose, 2>& eyes,
                                   const std::array<AsymmetricFov, 2>& fovs) {
  renderer::StereoRig rig;
  const glm::dquat head_inv = glm::inverse(glm::normalize(head.orientation));
  for (std::size_t i = 0; i < 2; ++i) {
    auto& e = rig.eyes[i];
    e.position_m = head_inv * (eyes[i].position_m - head.position_m);
    e.rotation = glm::mat3_cast(head_inv * glm::normalize(eyes[i].orientation));
    e.fov = {fovs[i].left_rad, fovs[i].right_rad, fovs[i].up_rad, fovs[i].down_rad};
  }
  return rig;
}

geometry::LabPose to_geometry(const StagePose& pose, bool valid) {
  geometry::LabPose p;
  p.position_m = pose.position_m;
  p.orientation = pose.orientation;
  p.valid = valid;
  return p;
}

std::optional<std::int64_t> choose_swapchain_format(const std::vector<std::int64_t>& offered) {
  for (const std::int64_t want : {kR8G8B8A8Srgb, kB8G8R8A8Srgb, kR8G8B8A8Unorm, kB8G8R8A8Unorm})
    if (std::find(offered.begin(), offered.end(), want) != offered.end()) return want;
  return std::nullopt;
}

}  // namespace curvlab::harness::xr
