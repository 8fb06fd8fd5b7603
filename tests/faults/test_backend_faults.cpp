// Faults inside the real backends, injected where a GPU or a runtime fails:
// the test Vulkan layer makes vkQueueSubmit or vkWaitForFences of the real
// headless backend return VK_ERROR_DEVICE_LOST at the N-th call. What must
// hold (docs/runner.md, "Faults"): the failing method throws
// runner::DeviceFailure naming the call and its result; the backend is
// then destroyed without throwing or terminating, pending frames included.
#include "fault_env.hpp"
#include "../renderer/stimulus_fixtures.hpp"

#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/renderer/scene.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>

namespace {

using namespace curvlab;
namespace rn = harness::runner;
using curvlab::testing::VulkanFault;

std::unique_ptr<rn::HeadlessDisplay> small_headless() {
  rn::HeadlessOptions o;
  o.software = true;
  o.width_px = 64;
  o.height_px = 64;
  auto made = rn::HeadlessDisplay::create(o);
  EXPECT_TRUE(made.has_value()) << (made ? "" : made.error().message);
  return made ? std::move(made).value() : nullptr;
}

// Draws frames (the head moving, so none is skipped as unchanged) until the
// backend throws; returns the failure and how many frames were drawn before.
std::pair<std::optional<harness::io::DeviceFailure>, int> draw_until_failure(rn::HeadlessDisplay& backend, int frames) {
  const auto s = renderer::fixtures::make(geometry::SpaceKind::E3, renderer::fixtures::SceneKind::stick);
  for (int i = 0; i < frames; ++i) {
    const auto timing = backend.begin_frame();
    renderer::FrameDescription f;
    f.space = s.space;
    f.head = s.head;
    f.head.m[3][0] += 1e-3 * i;  // a little sideways each frame
    f.rig = backend.rig(*timing, 0.063);
    f.width_px = 64;
    f.height_px = 64;
    try {
      (void)backend.submit(s.scene, f, harness::io::Overlay{harness::io::Phase::stimulus, "", false}, true);
    } catch (const harness::io::DeviceFailure& failure) {
      return {failure, i};
    }
  }
  return {std::nullopt, frames};
}

}  // namespace

TEST(HeadlessFaults, HealthyRunDrawsEveryFrame) {
  // The layer on, no fault due: the path the fault tests change is sound.
  const VulkanFault fault("vkQueueSubmit@100000");
  auto backend = small_headless();
  ASSERT_TRUE(backend);
  const auto [failure, drawn] = draw_until_failure(*backend, 6);
  EXPECT_FALSE(failure) << failure->what();
  EXPECT_EQ(drawn, 6);
}

TEST(HeadlessFaults, DeviceLostInQueueSubmitThrowsDeviceFailureNamingIt) {
  const VulkanFault fault("vkQueueSubmit@5");
  auto backend = small_headless();
  ASSERT_TRUE(backend);
  const auto [failure, drawn] = draw_until_failure(*backend, 20);
  ASSERT_TRUE(failure) << "no failure in 20 frames";
  EXPECT_GE(drawn, 1);  // earlier frames were drawn
  EXPECT_EQ(failure->call, "vkQueueSubmit");
  EXPECT_EQ(failure->result, "VK_ERROR_DEVICE_LOST");
  EXPECT_EQ(std::string(failure->what()).rfind("vkQueueSubmit: VK_ERROR_DEVICE_LOST", 0), 0u) << failure->what();
  // The device stays lost: the next frame fails the same way.
  const auto [again, none] = draw_until_failure(*backend, 1);
  ASSERT_TRUE(again);
  EXPECT_EQ(none, 0);
  EXPECT_EQ(again->result, "VK_ERROR_DEVICE_LOST");
  backend.reset();  // teardown waits on a lost device without throwing
  SUCCEED();
}

TEST(HeadlessFaults, DeviceLostWhileWaitingForTheFrameLeavesItPendingAndTeardownStillEnds) {
  // The frame is submitted, then its fence wait reports the loss: the
  // renderer's frame slot stays pending, and the destructors wait on it
  // again (raw calls, results ignored). Waiting with the throwing RAII call
  // there would end the process in std::terminate.
  const VulkanFault fault("vkWaitForFences@4");
  auto backend = small_headless();
  ASSERT_TRUE(backend);
  const auto [failure, drawn] = draw_until_failure(*backend, 20);
  ASSERT_TRUE(failure) << "no failure in 20 frames";
  EXPECT_GE(drawn, 1);
  EXPECT_EQ(failure->call, "vkWaitForFences");
  EXPECT_EQ(failure->result, "VK_ERROR_DEVICE_LOST");
  backend.reset();
  SUCCEED();
}

TEST(HeadlessFaults, OutOfDeviceMemoryIsNamedToo) {
  const VulkanFault fault("vkQueueSubmit@3:VK_ERROR_OUT_OF_DEVICE_MEMORY");
  auto backend = small_headless();
  ASSERT_TRUE(backend);
  const auto [failure, drawn] = draw_until_failure(*backend, 20);
  ASSERT_TRUE(failure);
  EXPECT_EQ(std::string(failure->what()).rfind("vkQueueSubmit: VK_ERROR_OUT_OF_DEVICE_MEMORY", 0), 0u)
      << failure->what();
  (void)drawn;
}
