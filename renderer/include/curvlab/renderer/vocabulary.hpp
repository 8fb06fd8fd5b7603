// What a view and a stimulus are named by, for the renderer and every layer
// above it: the projection, which eyes see the scene, and the marks along the
// cue stick, each with its names (geometry/enum_names.hpp). The view presets
// and the tracking algorithms, which geometry's perception model and trackers
// use, are geometry's (perception.hpp, tracking.hpp). Header-only, so that the
// protocol layer names these types without linking Vulkan.
#pragma once

#include "curvlab/geometry/enum_names.hpp"
#include "curvlab/geometry/perception.hpp"

#include <array>
#include <cstdlib>
#include <optional>
#include <string_view>

namespace curvlab::renderer {

// Tourist: each eye a curved-space translation of the nose, true optics;
// native: the nose's azimuthal-equidistant image seen by Euclidean eyes
// (DESIGN.md §4, docs/renderer.md "The views").
enum class Projection { tourist, native };
inline constexpr std::array kProjections{Projection::tourist, Projection::native};

constexpr std::string_view to_string(Projection projection) {
  switch (projection) {
    case Projection::tourist: return "tourist";
    case Projection::native: return "native";
  }
  return "?";
}
constexpr std::optional<Projection> parse_projection(std::string_view text) {
  return geometry::parse_name(kProjections, text);
}

// Which eyes see the scene; the other shows the background.
enum class EyeSelection { both, left, right, dominant };
inline constexpr std::array kEyeSelections{EyeSelection::both, EyeSelection::left, EyeSelection::right,
                                           EyeSelection::dominant};

constexpr std::string_view to_string(EyeSelection eyes) {
  switch (eyes) {
    case EyeSelection::both: return "both";
    case EyeSelection::left: return "left";
    case EyeSelection::right: return "right";
    case EyeSelection::dominant: return "dominant";
  }
  return "?";
}
constexpr std::optional<EyeSelection> parse_eye_selection(std::string_view text) {
  return geometry::parse_name(kEyeSelections, text);
}

// Marks along the cue stick: none, or light rings at known positions
// (mesh.hpp, kStickRingFractions), which `curvlab measure` matches between
// the eyes.
enum class StickMarks { none, rings };
inline constexpr std::array kStickMarks{StickMarks::none, StickMarks::rings};

constexpr std::string_view to_string(StickMarks marks) {
  switch (marks) {
    case StickMarks::none: return "none";
    case StickMarks::rings: return "rings";
  }
  return "?";
}
constexpr std::optional<StickMarks> parse_stick_marks(std::string_view text) {
  return geometry::parse_name(kStickMarks, text);
}

// The projection and eyes a preset stands for (DESIGN.md §4: monocular =
// native, the dominant eye).
struct PresetViewing {
  Projection projection;
  EyeSelection eyes;
};
inline PresetViewing preset_viewing(geometry::ViewPreset preset) {
  switch (preset) {
    case geometry::ViewPreset::tourist: return {Projection::tourist, EyeSelection::both};
    case geometry::ViewPreset::native: return {Projection::native, EyeSelection::both};
    case geometry::ViewPreset::monocular: return {Projection::native, EyeSelection::dominant};
  }
  std::abort();  // not a ViewPreset: a broken contract
}

// What the perception model (geometry/perception.hpp) is given for a
// projection and an eye selection: with both eyes the projection's own
// preset; with one eye monocular, whatever the projection (no disparity).
inline geometry::ViewPreset perceived_preset(Projection projection, EyeSelection eyes) {
  switch (eyes) {
    case EyeSelection::both: break;
    case EyeSelection::left:
    case EyeSelection::right:
    case EyeSelection::dominant: return geometry::ViewPreset::monocular;
  }
  switch (projection) {
    case Projection::tourist: return geometry::ViewPreset::tourist;
    case Projection::native: return geometry::ViewPreset::native;
  }
  std::abort();  // not a Projection: a broken contract
}

}  // namespace curvlab::renderer
