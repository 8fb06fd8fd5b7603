#include "swapchains.hpp"

#include "curvlab/harness/io/frame.hpp"
#include "curvlab/harness/xr/stereo.hpp"

#include <iostream>
#include <string>

namespace curvlab::harness::xr {

using harness::Done;
using harness::Error;
using harness::Result;

namespace {

// Two-call enumeration of the swapchain formats the runtime offers.
Result<std::vector<std::int64_t>> swapchain_formats(XrSession session) {
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateSwapchainFormats(session, 0, &count, nullptr); XR_FAILED(r))
    return failure_of(r, "xrEnumerateSwapchainFormats");
  std::vector<std::int64_t> formats(count);
  if (const XrResult r = xrEnumerateSwapchainFormats(session, count, &count, formats.data()); XR_FAILED(r))
    return failure_of(r, "xrEnumerateSwapchainFormats");
  return formats;
}

// The stereo view configuration's two views (the recommended image sizes).
Result<std::vector<XrViewConfigurationView>> stereo_views(XrInstance xr, XrSystemId sys) {
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateViewConfigurationViews(xr, sys, kViewConfig, 0, &count, nullptr);
      XR_FAILED(r))
    return failure_of(r, "xrEnumerateViewConfigurationViews");
  std::vector<XrViewConfigurationView> config(count, tagged<XrViewConfigurationView>(XR_TYPE_VIEW_CONFIGURATION_VIEW));
  if (const XrResult r = xrEnumerateViewConfigurationViews(xr, sys, kViewConfig, count, &count, config.data());
      XR_FAILED(r))
    return failure_of(r, "xrEnumerateViewConfigurationViews");
  if (count != 2)
    return Error{Error::Kind::device, "the headset's stereo view configuration has " + std::to_string(count) +
                                          " views; curvlab needs 2"};
  return config;
}

}  // namespace

Result<EyeSwapchains> EyeSwapchains::create(const Session& session) {
  auto views = stereo_views(session.instance().handle(), session.system());
  if (!views) return views.error();
  auto formats = swapchain_formats(session.handle());
  if (!formats) return formats.error();
  const auto format = choose_swapchain_format(formats.value());
  if (!format)
    return Error{Error::Kind::device, "the OpenXR runtime offers no 8-bit RGBA or BGRA swapchain format "
                                      "(xrEnumerateSwapchainFormats); curvlab cannot show its images"};
  EyeSwapchains out;
  out.format_ = *format;
  for (std::size_t i = 0; i < 2; ++i)
    if (auto r = out.make(session, out.eyes_[i], views.value()[i]); !r) return r.error();
  return out;
}

Result<Done> EyeSwapchains::make(const Session& session, Eye& eye, const XrViewConfigurationView& view) const {
  eye.width = view.recommendedImageRectWidth;
  eye.height = view.recommendedImageRectHeight;
  // TRANSFER_SRC: the operator window's copies (OperatorMirror).
  auto made = make_swapchain(session, format_, eye.width, eye.height,
                             XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT |
                                 XR_SWAPCHAIN_USAGE_TRANSFER_SRC_BIT);
  if (!made) return made.error();
  eye.handle = std::move(made.value().handle);
  eye.images = std::move(made.value().images);
  return Done{};
}

Result<MadeSwapchain> make_swapchain(const Session& session, std::int64_t format, std::uint32_t width,
                                     std::uint32_t height, XrSwapchainUsageFlags usage) {
  auto info = tagged<XrSwapchainCreateInfo>(XR_TYPE_SWAPCHAIN_CREATE_INFO);
  info.usageFlags = usage;
  info.format = format;
  info.sampleCount = 1;
  info.width = width;
  info.height = height;
  info.faceCount = 1;
  info.arraySize = 1;
  info.mipCount = 1;
  MadeSwapchain out;
  if (const XrResult r = xrCreateSwapchain(session.handle(), &info, out.handle.out()); XR_FAILED(r))
    return failure_of(r, "xrCreateSwapchain");
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateSwapchainImages(out.handle.get(), 0, &count, nullptr); XR_FAILED(r))
    return failure_of(r, "xrEnumerateSwapchainImages");
  out.images.assign(count, tagged<XrSwapchainImageVulkan2KHR>(XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR));
  if (const XrResult r = xrEnumerateSwapchainImages(
          out.handle.get(), count, &count, reinterpret_cast<XrSwapchainImageBaseHeader*>(out.images.data()));
      XR_FAILED(r))
    return failure_of(r, "xrEnumerateSwapchainImages");
  return out;
}

XrSwapchainSubImage EyeSwapchains::sub_image(std::size_t i) const {
  XrSwapchainSubImage sub{};
  sub.swapchain = eyes_[i].handle.get();
  sub.imageRect = {{0, 0}, {static_cast<std::int32_t>(eyes_[i].width), static_cast<std::int32_t>(eyes_[i].height)}};
  sub.imageArrayIndex = 0;
  return sub;
}

std::array<vk::Image, 2> EyeSwapchains::acquire(Session& session) {
  std::array<vk::Image, 2> images{};
  for (std::size_t i = 0; i < 2; ++i) {
    Eye& eye = eyes_[i];
    std::uint32_t index = 0;
    auto acquire = tagged<XrSwapchainImageAcquireInfo>(XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO);
    if (const XrResult r = xrAcquireSwapchainImage(eye.handle.get(), &acquire, &index); XR_FAILED(r)) {
      release();
      session.fail(r, "xrAcquireSwapchainImage");  // the display's destructor ends the begun frame
    }
    acquired_[i] = true;
    try {
      wait_swapchain_image(session, eye.handle.get(), wait_said_);
    } catch (const harness::io::DeviceFailure&) {
      // A waited image is released by release(); one the wait never got
      // is not (the runtime refuses it): the frame is lost either way.
      acquired_[i] = false;
      release();
      throw;
    }
    images[i] = eye.images[index].image;
  }
  return images;
}

void EyeSwapchains::release() {
  for (std::size_t i = 0; i < 2; ++i) {
    if (!acquired_[i]) continue;
    auto info = tagged<XrSwapchainImageReleaseInfo>(XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO);
    (void)xrReleaseSwapchainImage(eyes_[i].handle.get(), &info);
    acquired_[i] = false;
  }
}

void wait_swapchain_image(Session& session, XrSwapchain swapchain, bool& said) {
  // XR_TIMEOUT_EXPIRED is a success code: the image is not yet the
  // application's (OpenXR 1.0 §10.1, xrWaitSwapchainImage), so it is waited
  // again, and a wait past kLimit is a failure of the compositor.
  constexpr XrDuration kStep = 250'000'000, kLimit = 5'000'000'000;
  auto wait = tagged<XrSwapchainImageWaitInfo>(XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO);
  wait.timeout = kStep;
  for (XrDuration waited = 0;; waited += kStep) {
    const XrResult r = xrWaitSwapchainImage(swapchain, &wait);
    if (XR_FAILED(r)) session.fail(r, "xrWaitSwapchainImage");
    if (r != XR_TIMEOUT_EXPIRED) return;
    if (!said) {
      std::cerr << "curvlab: xr: the compositor has held a swapchain image for more than " << kStep / 1'000'000
                << " ms; waiting for it\n";
      said = true;
    }
    if (waited + kStep >= kLimit) session.fail(XR_TIMEOUT_EXPIRED, "xrWaitSwapchainImage");
  }
}

}  // namespace curvlab::harness::xr
