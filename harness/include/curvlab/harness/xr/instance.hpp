// The OpenXR instance path: loader → API layers and extensions → instance
// with XR_KHR_vulkan_enable2 → head-mounted-display system. On a machine
// without a runtime this fails at xrCreateInstance (or at the extension
// query) with XR_ERROR_RUNTIME_UNAVAILABLE; the failure is a value (the
// harness's Error, result.hpp) whose message names the result and what to
// install.
#pragma once

#include "curvlab/harness/result.hpp"
#include "curvlab/harness/xr/actions.hpp"

#include <openxr/openxr.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::xr {

// The name of an XrResult ("XR_ERROR_RUNTIME_UNAVAILABLE"), without an
// instance (xrResultToString needs one, which is exactly what is missing
// when the runtime is). Unknown codes read "XR_RESULT_<n>".
std::string result_name(XrResult result);

// Every failure here is a harness::Error: kind `device` when there is no
// runtime or headset to answer (XR_ERROR_RUNTIME_UNAVAILABLE,
// XR_ERROR_RUNTIME_FAILURE, XR_ERROR_FORM_FACTOR_UNAVAILABLE, a missing
// extension or API version), `api` for any other failing call. Its message
// reads "CALL returned NAME (CODE): what to do"; failed_call() reads the
// call and result back (for `curvlab xr-check --json`).
struct FailedCall {
  std::string call;  // the OpenXR function that failed
  XrResult result = XR_SUCCESS;
};
std::optional<FailedCall> failed_call(const harness::Error& error);

struct ProbeReport {
  std::vector<std::string> api_layers;
  std::vector<std::string> extensions;
  std::string runtime_name;
  std::string runtime_version;
  std::string system_name;
  std::uint32_t vendor_id = 0;
  bool orientation_tracking = false;
  bool position_tracking = false;
  std::uint32_t max_swapchain_width = 0;
  std::uint32_t max_swapchain_height = 0;
};

// Owns one XrInstance (and the XrSystemId found for the HMD). Move-only;
// destroyed by the destructor. Not thread-safe.
class Instance {
 public:
  static harness::Result<Instance> create(const std::string& application_name);
  // With further extensions besides XR_KHR_vulkan_enable2 (each must be
  // offered by the runtime: check with available_extensions()).
  static harness::Result<Instance> create(const std::string& application_name,
                                          const std::vector<std::string>& extra_extensions);
  Instance(Instance&& other) noexcept;
  Instance& operator=(Instance&& other) noexcept;
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;
  ~Instance();

  [[nodiscard]] XrInstance handle() const { return instance_; }
  // The head-mounted display; fails with XR_ERROR_FORM_FACTOR_UNAVAILABLE
  // while the headset is off or unplugged.
  harness::Result<XrSystemId> hmd_system() const;
  [[nodiscard]] std::string path_string(XrPath path) const;

 private:
  explicit Instance(XrInstance instance) : instance_(instance) {}
  XrInstance instance_ = XR_NULL_HANDLE;
};

// Owns an XrActionSet and its actions (destroyed with the set). Move-only.
class ActionSet {
 public:
  // Creates the set and actions and suggests the bindings of every profile.
  static harness::Result<ActionSet> create(const Instance& instance, const ActionSetDef& def);
  ActionSet(ActionSet&& other) noexcept;
  ActionSet& operator=(ActionSet&& other) noexcept;
  ActionSet(const ActionSet&) = delete;
  ActionSet& operator=(const ActionSet&) = delete;
  ~ActionSet();

  [[nodiscard]] XrActionSet handle() const { return set_; }
  [[nodiscard]] XrAction action(std::string_view name) const;

 private:
  ActionSet() = default;
  XrActionSet set_ = XR_NULL_HANDLE;
  std::vector<std::pair<std::string, XrAction>> actions_;
};

// The failure of `call` with `result`, its message naming the result and
// what to do (the same wording as every other failure here).
harness::Error failure_of(XrResult result, const char* call);

// A zeroed OpenXR input/output struct with its type tag set.
template <class T>
T tagged(XrStructureType type) {
  T value{};
  value.type = type;
  return value;
}

// Results after which the session cannot go on, whichever call returned
// them; other failures of per-frame queries (a button, a pose) are logged or
// taken as lost tracking, and the session continues.
inline bool fatal(XrResult r) {
  return r == XR_ERROR_SESSION_LOST || r == XR_ERROR_INSTANCE_LOST || r == XR_ERROR_RUNTIME_FAILURE;
}

// An extension's function, through the loader.
template <class F>
XrResult load(XrInstance instance, const char* name, F& fn) {
  return xrGetInstanceProcAddr(instance, name, reinterpret_cast<PFN_xrVoidFunction*>(&fn));
}

// The instance extensions the loader and runtime offer; this is where a
// missing runtime first shows (XR_ERROR_RUNTIME_UNAVAILABLE).
harness::Result<std::vector<std::string>> available_extensions();

// Runs the whole path up to the system (no session: that needs the
// renderer's Vulkan device) and describes what it found.
harness::Result<ProbeReport> probe(const std::string& application_name);

}  // namespace curvlab::harness::xr
