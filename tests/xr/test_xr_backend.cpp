// The OpenXR backend up to the hardware boundary: the factory's failure
// without a runtime (DESIGN.md §9: XR_ERROR_RUNTIME_UNAVAILABLE), and the pure
// conversions it feeds the renderer and the session log.
#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/xr/backend.hpp"
#include "curvlab/harness/xr/gaze.hpp"
#include "curvlab/harness/xr/stereo.hpp"

#include <vulkan/vulkan_core.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <cmath>
#include <numbers>

namespace {

using namespace curvlab::harness::xr;

TEST(XrBackend, WithoutARuntimeNamesTheResultAndTheFixAndWritesNothing) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("curvlab_xr_backend_test_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto old = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  curvlab::harness::io::SteadyClock clock;
  XrBackendOptions options;
  options.clock = &clock;
  auto made = make_xr_backend(options);
  std::filesystem::current_path(old);
  const bool empty = std::filesystem::is_empty(dir);
  std::filesystem::remove_all(dir);
  if (made) GTEST_SKIP() << "an OpenXR runtime and headset are present";
  EXPECT_EQ(made.error().kind, curvlab::harness::Error::Kind::device);
  const auto& message = made.error().message;
  EXPECT_NE(message.find("XR_ERROR_RUNTIME_UNAVAILABLE (-51)"), std::string::npos) << message;
  EXPECT_NE(message.find("Monado"), std::string::npos) << message;
  EXPECT_NE(message.find("SteamVR"), std::string::npos) << message;
  EXPECT_NE(message.find("active_runtime.json"), std::string::npos) << message;
  EXPECT_TRUE(empty) << "the OpenXR backend wrote files before failing";
}

TEST(XrBackend, WithoutAClockIsRefused) {
  auto made = make_xr_backend(XrBackendOptions{});
  ASSERT_FALSE(made.has_value());
  EXPECT_NE(made.error().message.find("clock"), std::string::npos);
}

// Views of a head turned 30° left and tilted 10° down, eyes 64 mm apart and
// 2 mm forward of the VIEW origin, each eye toed in by 1°: the offsets come
// back in the head's frame whatever the head's pose.
TEST(StereoRig, EyeOffsetsAreRelativeToTheHead) {
  const double deg = std::numbers::pi / 180.0;
  StagePose head;
  head.position_m = {0.3, 1.6, -0.2};
  head.orientation = glm::angleAxis(30 * deg, glm::dvec3(0, 1, 0)) *
                     glm::angleAxis(-10 * deg, glm::dvec3(1, 0, 0));
  const std::array<glm::dvec3, 2> local{glm::dvec3(-0.032, 0.0, -0.002), glm::dvec3(0.032, 0.0, -0.002)};
  const std::array<glm::dquat, 2> toe{glm::angleAxis(-1 * deg, glm::dvec3(0, 1, 0)),
                                      glm::angleAxis(1 * deg, glm::dvec3(0, 1, 0))};
  std::array<StagePose, 2> eyes;
  for (std::size_t i = 0; i < 2; ++i) {
    eyes[i].position_m = head.position_m + head.orientation * local[i];
    eyes[i].orientation = head.orientation * toe[i];
  }
  const std::array<AsymmetricFov, 2> fovs{AsymmetricFov{-0.9, 0.7, 0.8, -0.85},
                                          AsymmetricFov{-0.7, 0.9, 0.8, -0.85}};
  const auto rig = rig_from_views(head, eyes, fovs);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(rig.eyes[i].position_m.x, local[i].x, 1e-12);
    EXPECT_NEAR(rig.eyes[i].position_m.y, local[i].y, 1e-12);
    EXPECT_NEAR(rig.eyes[i].position_m.z, local[i].z, 1e-12);
    // The eye's forward axis, seen from the head: turned by ∓1° about y.
    const glm::dvec3 fwd = rig.eyes[i].rotation * glm::dvec3(0, 0, -1);
    const double expected = (i == 0 ? -1.0 : 1.0) * deg;
    EXPECT_NEAR(std::atan2(-fwd.x, -fwd.z), expected, 1e-12);
    EXPECT_NEAR(fwd.y, 0.0, 1e-12);
    EXPECT_DOUBLE_EQ(rig.eyes[i].fov.angle_left_rad, fovs[i].left_rad);
    EXPECT_DOUBLE_EQ(rig.eyes[i].fov.angle_right_rad, fovs[i].right_rad);
    EXPECT_DOUBLE_EQ(rig.eyes[i].fov.angle_up_rad, fovs[i].up_rad);
    EXPECT_DOUBLE_EQ(rig.eyes[i].fov.angle_down_rad, fovs[i].down_rad);
  }
}

TEST(StereoRig, GeometryPoseKeepsValidity) {
  StagePose p;
  p.position_m = {1, 2, 3};
  const auto lost = to_geometry(p, false);
  EXPECT_FALSE(lost.valid);
  EXPECT_EQ(lost.position_m, glm::dvec3(1, 2, 3));
  EXPECT_TRUE(to_geometry(p, true).valid);
}

TEST(SwapchainFormat, PrefersSrgbThenTheBytesTheRendererWrites) {
  EXPECT_EQ(choose_swapchain_format({VK_FORMAT_B8G8R8A8_SRGB, VK_FORMAT_R8G8B8A8_SRGB,
                                     VK_FORMAT_R8G8B8A8_UNORM}),
            VK_FORMAT_R8G8B8A8_SRGB);
  EXPECT_EQ(choose_swapchain_format({VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_SRGB}),
            VK_FORMAT_B8G8R8A8_SRGB);
  EXPECT_EQ(choose_swapchain_format({VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8G8B8A8_UNORM}),
            VK_FORMAT_R8G8B8A8_UNORM);
  EXPECT_EQ(choose_swapchain_format({VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_B8G8R8A8_UNORM}),
            VK_FORMAT_B8G8R8A8_UNORM);
  EXPECT_EQ(choose_swapchain_format({VK_FORMAT_B8G8R8A8_SRGB}), VK_FORMAT_B8G8R8A8_SRGB);
  EXPECT_FALSE(choose_swapchain_format({VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_A2B10G10R10_UNORM_PACK32}));
  EXPECT_FALSE(choose_swapchain_format({}));
}

TEST(XrClockMap, KeepsTheRuntimesDifferences) {
  XrClockMap map;
  EXPECT_FALSE(map.anchored());
  map.anchor(5'000'000'000, 123'456'789);
  EXPECT_TRUE(map.anchored());
  EXPECT_EQ(map.to_session(5'000'000'000), 123'456'789);
  EXPECT_EQ(map.to_session(5'011'111'111) - map.to_session(5'000'000'000), 11'111'111);
  EXPECT_EQ(map.to_xr(map.to_session(7'000'000'001)), 7'000'000'001);
}

// The measured vergence of two gaze rays: read in the head's frame, so a
// turned and tilted head changes nothing; eyes fixating a point D ahead
// converge by 2 atan(IPD / 2D) and imply D; eyes turned outward diverge
// (negative) and imply no distance.
TEST(XrGaze, VergenceOfTwoRaysIsSignedAndImpliesTheFixationDistance) {
  const double pi = std::numbers::pi;
  StagePose head;
  head.position_m = {0.3, 1.6, 0.4};
  head.orientation = glm::angleAxis(0.5, glm::dvec3(0, 1, 0)) * glm::angleAxis(-0.44, glm::dvec3(1, 0, 0));
  const glm::dvec3 right = head.orientation * glm::dvec3(0.032, 0, 0);
  const glm::dvec3 forward = head.orientation * glm::dvec3(0, 0, -1);
  auto ray = [](glm::dvec3 o, glm::dvec3 d) {
    curvlab::harness::io::GazeRay r;
    r.valid = true;
    r.origin_m = o;
    r.direction = glm::normalize(d);
    return r;
  };
  for (const double d_m : {0.4, 1.0, 3.0, 20.0}) {
    const glm::dvec3 target = head.position_m + d_m * forward;
    const auto v = vergence_of(head, ray(head.position_m - right, target - (head.position_m - right)),
                               ray(head.position_m + right, target - (head.position_m + right)));
    EXPECT_NEAR(v.angle_rad, 2.0 * std::atan(0.032 / d_m), 1e-12) << d_m;
    ASSERT_TRUE(v.distance_m.has_value());
    EXPECT_NEAR(*v.distance_m, d_m, 1e-9 * d_m);
  }
  // 0.5° beyond parallel: each eye turned 0.25° outward.
  const double out = 0.25 * pi / 180.0;
  const glm::dvec3 up = head.orientation * glm::dvec3(0, 1, 0);
  const auto diverging = vergence_of(head, ray(head.position_m - right, glm::angleAxis(out, up) * forward),
                                     ray(head.position_m + right, glm::angleAxis(-out, up) * forward));
  EXPECT_NEAR(diverging.angle_rad, -0.5 * pi / 180.0, 1e-12);
  EXPECT_FALSE(diverging.distance_m.has_value());
  const auto parallel = vergence_of(head, ray(head.position_m - right, forward), ray(head.position_m + right, forward));
  EXPECT_NEAR(parallel.angle_rad, 0.0, 1e-12);
  EXPECT_FALSE(parallel.distance_m.has_value());
}

// The ray of a gaze pose runs along the pose's -Z axis from its position.
TEST(XrGaze, GazeRayRunsAlongThePosesMinusZ) {
  XrPosef pose{};
  // 90° about +y: -Z turns to -X.
  pose.orientation = {0.0f, std::sin(static_cast<float>(std::numbers::pi) / 4.0f), 0.0f,
                      std::cos(static_cast<float>(std::numbers::pi) / 4.0f)};
  pose.position = {1.0f, 2.0f, 3.0f};
  const auto r = gaze_ray(pose, true, 0.5);
  EXPECT_NEAR(r.direction.x, -1.0, 1e-6);
  EXPECT_NEAR(r.direction.z, 0.0, 1e-6);
  EXPECT_EQ(r.origin_m, glm::dvec3(1.0, 2.0, 3.0));
  EXPECT_EQ(r.confidence, 0.5);
}

}  // namespace
