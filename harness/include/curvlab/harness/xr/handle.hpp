// Ownership of OpenXR child handles (sessions, spaces, swapchains): one
// move-only owner each, destroyed by its destructor (STYLE.md, "Resources and
// errors").
#pragma once

#include <openxr/openxr.h>

#include <utility>

namespace curvlab::harness::xr {

// Owns one OpenXR child handle. Move-only; destroyed by the destructor.
template <class H, XrResult (*Destroy)(H)>
class Handle {
 public:
  Handle() = default;
  Handle(Handle&& o) noexcept : h_(std::exchange(o.h_, XR_NULL_HANDLE)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      h_ = std::exchange(o.h_, XR_NULL_HANDLE);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }
  void reset() noexcept {
    if (h_ != XR_NULL_HANDLE) (void)Destroy(h_);
    h_ = XR_NULL_HANDLE;
  }
  [[nodiscard]] H get() const { return h_; }
  H* out() {
    reset();
    return &h_;
  }

 private:
  H h_ = XR_NULL_HANDLE;
};

using SessionHandle = Handle<XrSession, xrDestroySession>;
using SpaceHandle = Handle<XrSpace, xrDestroySpace>;
using SwapchainHandle = Handle<XrSwapchain, xrDestroySwapchain>;

}  // namespace curvlab::harness::xr
