// The interaction profiles of the OpenXR 1.0 specification (§6.4,
// "Interaction Profile Paths"): which profiles exist, which input and output
// paths each one offers under which top-level user paths, and the names a
// runtime shows for them. Pure data and lookups, no state.
#pragma once

#include <string>

namespace curvlab::test_runtime {

inline constexpr const char* kTouch = "/interaction_profiles/oculus/touch_controller";
inline constexpr const char* kSimple = "/interaction_profiles/khr/simple_controller";

// Whether `profile` is one of the nine profiles OpenXR 1.0 defines.
bool known_profile(const std::string& profile);

// Whether the profile offers `binding` (a full path such as
// "/user/hand/left/input/squeeze/value"). An identifier without its
// component ("/user/hand/left/input/squeeze") is offered when the profile has
// any component of it: the specification lets the runtime pick one.
bool profile_has(const std::string& profile, const std::string& binding);

// Whether `path` is one of the specification's top-level user paths
// (/user/hand/left, /user/hand/right, /user/head, /user/gamepad,
// /user/treadmill).
bool top_level_user_path(const std::string& path);

// The name a runtime shows for a source path under `profile`, made of the
// parts asked for: the user path ("Left Hand"), the profile ("Oculus Touch
// Controller") and the component ("Squeeze Value"), joined by spaces.
std::string localized_source_name(const std::string& profile, const std::string& source, bool user_part,
                                  bool profile_part, bool component_part);

}  // namespace curvlab::test_runtime
