// The pure parts of the OpenXR backend (xr/backend.hpp), testable without a
// runtime: views located in STAGE space → the renderer's eye offsets relative
// to the head; swapchain format negotiation; XrTime → session clock.
#pragma once

#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/xr/views.hpp"
#include "curvlab/renderer/view.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace curvlab::harness::xr {

// Eye offsets and fields of view as the renderer takes them (DESIGN.md §4):
// each eye's position and rotation relative to the head (the VIEW space,
// between the eyes), from poses all located in the same space at the same
// time. Holds for any head orientation: offsets are expressed in the head's
// frame, so the rig turns with the head.
renderer::StereoRig rig_from_views(const StagePose& head, const std::array<StagePose, 2>& eyes,
                                   const std::array<AsymmetricFov, 2>& fovs);

// A lab pose in geometry's type (the tracker's input).
geometry::LabPose to_geometry(const StagePose& pose, bool valid);

// VkFormat values (as OpenXR's xrEnumerateSwapchainFormats returns them) in
// curvlab's order of preference: sRGB first, as the OpenXR specification
// advises for colour (XR_KHR_vulkan_enable2: the runtime takes UNORM values
// as linear) — R8G8B8A8_SRGB, which the renderer's eye images are copied into
// byte for byte, then B8G8R8A8_SRGB (blitted); then the UNORM formats
// (blitted, receiving linear values). nullopt: the runtime offers none.
std::optional<std::int64_t> choose_swapchain_format(const std::vector<std::int64_t>& offered);

// XrTime (runtime nanoseconds) → the session clock. With
// XR_KHR_convert_timespec_time the runtime converts to CLOCK_MONOTONIC and an
// offset measured against the session clock maps that; without it the
// offset is anchored once, at the first frame, by taking its predicted
// display time to be one display period after the moment xrWaitFrame
// returned (docs/lab.md). Either way later times keep the runtime's exact
// differences. Not thread-safe.
class XrClockMap {
 public:
  // Anchors the map: xr_ns (an XrTime) happens at session_ns.
  void anchor(std::int64_t xr_ns, std::int64_t session_ns) {
    offset_ns_ = session_ns - xr_ns;
    anchored_ = true;
  }
  [[nodiscard]] bool anchored() const { return anchored_; }
  [[nodiscard]] std::int64_t to_session(std::int64_t xr_ns) const { return xr_ns + offset_ns_; }
  [[nodiscard]] std::int64_t to_xr(std::int64_t session_ns) const { return session_ns - offset_ns_; }

 private:
  std::int64_t offset_ns_ = 0;
  bool anchored_ = false;
};

}  // namespace curvlab::harness::xr
