#include "profiles.hpp"

#include <algorithm>
#include <cctype>
#include <vector>

namespace curvlab::test_runtime {
namespace {

constexpr const char* kLeft = "/user/hand/left";
constexpr const char* kRight = "/user/hand/right";

// One profile: the inputs and outputs it has under each of its user paths
// (relative to the user path, e.g. "input/select/click").
struct Profile {
  const char* path;
  const char* name;
  std::vector<std::pair<std::string, std::vector<std::string>>> users;
};

using Paths = std::vector<std::string>;

Paths joined(Paths a, const Paths& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// The same set for both hands.
std::vector<std::pair<std::string, Paths>> hands(const Paths& both) { return {{kLeft, both}, {kRight, both}}; }

const std::vector<Profile>& profiles() {
  static const Paths trackpad = {"input/trackpad/x", "input/trackpad/y", "input/trackpad/click",
                                 "input/trackpad/touch"};
  static const Paths poses = {"input/grip/pose", "input/aim/pose"};
  static const Paths thumbstick = {"input/thumbstick/x", "input/thumbstick/y", "input/thumbstick/click",
                                   "input/thumbstick/touch"};
  static const Paths touch_both = joined(joined({"input/squeeze/value", "input/trigger/value", "input/trigger/touch",
                                                 "input/thumbrest/touch", "output/haptic"},
                                                thumbstick),
                                         poses);
  static const std::vector<Profile> all = {
      {kSimple, "Simple Controller",
       hands(joined({"input/select/click", "input/menu/click", "output/haptic"}, poses))},
      {"/interaction_profiles/google/daydream_controller", "Daydream Controller",
       hands(joined(joined({"input/select/click"}, trackpad), poses))},
      {"/interaction_profiles/htc/vive_controller", "Vive Controller",
       hands(joined(joined({"input/system/click", "input/squeeze/click", "input/menu/click", "input/trigger/click",
                            "input/trigger/value", "output/haptic"},
                           trackpad),
                    poses))},
      {"/interaction_profiles/htc/vive_pro", "Vive Pro",
       {{"/user/head",
         {"input/system/click", "input/volume_up/click", "input/volume_down/click", "input/mute_mic/click"}}}},
      {"/interaction_profiles/microsoft/motion_controller", "Mixed Reality Motion Controller",
       hands(joined(joined(joined({"input/menu/click", "input/squeeze/click", "input/trigger/value", "output/haptic"},
                                  {"input/thumbstick/x", "input/thumbstick/y", "input/thumbstick/click"}),
                           trackpad),
                    poses))},
      {"/interaction_profiles/microsoft/xbox_controller", "Xbox Controller",
       {{"/user/gamepad",
         {"input/menu/click", "input/view/click", "input/a/click",
          "input/b/click", "input/x/click", "input/y/click",
          "input/dpad_down/click", "input/dpad_right/click", "input/dpad_up/click",
          "input/dpad_left/click", "input/shoulder_left/click", "input/shoulder_right/click",
          "input/thumbstick_left/click", "input/thumbstick_right/click", "input/trigger_left/value",
          "input/trigger_right/value", "input/thumbstick_left/x", "input/thumbstick_left/y",
          "input/thumbstick_right/x", "input/thumbstick_right/y", "output/haptic_left",
          "output/haptic_right", "output/haptic_left_trigger", "output/haptic_right_trigger"}}}},
      {"/interaction_profiles/oculus/go_controller", "Go Controller",
       hands(joined(joined({"input/system/click", "input/trigger/click", "input/back/click"}, trackpad), poses))},
      {kTouch, "Oculus Touch Controller",
       {{kLeft, joined({"input/x/click", "input/x/touch", "input/y/click", "input/y/touch", "input/menu/click"},
                       touch_both)},
        {kRight, joined({"input/a/click", "input/a/touch", "input/b/click", "input/b/touch", "input/system/click"},
                        touch_both)}}},
      {"/interaction_profiles/valve/index_controller", "Index Controller",
       hands(joined(joined({"input/system/click", "input/system/touch", "input/a/click", "input/a/touch",
                            "input/b/click", "input/b/touch", "input/squeeze/value", "input/squeeze/force",
                            "input/trigger/click", "input/trigger/value", "input/trigger/touch",
                            "input/trackpad/x", "input/trackpad/y", "input/trackpad/force", "input/trackpad/touch",
                            "output/haptic"},
                           thumbstick),
                    poses))},
  };
  return all;
}

const Profile* find_profile(const std::string& path) {
  for (const Profile& p : profiles())
    if (path == p.path) return &p;
  return nullptr;
}

// "thumbstick_left/x" → "Thumbstick Left X".
std::string title_case(const std::string& text) {
  std::string out;
  bool start = true;
  for (const char c : text) {
    if (c == '/' || c == '_') {
      out += ' ';
      start = true;
    } else {
      out += start ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
      start = false;
    }
  }
  return out;
}

}  // namespace

bool known_profile(const std::string& profile) { return find_profile(profile) != nullptr; }

bool profile_has(const std::string& profile, const std::string& binding) {
  const Profile* p = find_profile(profile);
  if (p == nullptr) return false;
  for (const auto& [user, paths] : p->users) {
    if (binding.rfind(user + "/", 0) != 0) continue;
    const std::string rest = binding.substr(user.size() + 1);
    for (const std::string& leaf : paths)
      if (leaf == rest || (rest.rfind("input/", 0) == 0 && leaf.rfind(rest + "/", 0) == 0 &&
                           std::count(rest.begin(), rest.end(), '/') == 1))
        return true;
  }
  return false;
}

bool top_level_user_path(const std::string& path) {
  return path == kLeft || path == kRight || path == "/user/head" || path == "/user/gamepad" ||
         path == "/user/treadmill";
}

std::string localized_source_name(const std::string& profile, const std::string& source, bool user_part,
                                  bool profile_part, bool component_part) {
  std::vector<std::string> parts;
  const Profile* p = find_profile(profile);
  std::string user, component;
  for (const char* top : {kLeft, kRight, "/user/head", "/user/gamepad", "/user/treadmill"})
    if (source.rfind(std::string(top) + "/", 0) == 0) {
      user = top;
      component = source.substr(user.size() + 1);
    }
  if (component.rfind("input/", 0) == 0) component = component.substr(6);
  else if (component.rfind("output/", 0) == 0) component = component.substr(7);
  if (user_part && !user.empty())
    parts.push_back(user == kLeft ? "Left Hand" : user == kRight ? "Right Hand" : title_case(user.substr(6)));
  if (profile_part && p != nullptr) parts.emplace_back(p->name);
  if (component_part && !component.empty()) parts.push_back(title_case(component));
  std::string name;
  for (const std::string& part : parts) name += (name.empty() ? "" : " ") + part;
  return name;
}

}  // namespace curvlab::test_runtime
