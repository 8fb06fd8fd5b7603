// The eye geometry a frame was drawn with, between the renderer's StereoRig
// and the data layer's ViewGeometry (frames.eye_width_px, eye_height_px,
// eye_views): the session records what the backend reported, replay draws
// from what was recorded (DESIGN.md §4 "Eye model", §7).
#pragma once

#include "curvlab/harness/data/records.hpp"
#include "curvlab/harness/io/display.hpp"
#include "curvlab/renderer/view.hpp"

#include <cstdint>
#include <utility>

namespace curvlab::harness::runner {

// The record of `rig` drawn at `width_px` × `height_px` per eye.
data::ViewGeometry record_view_geometry(const renderer::StereoRig& rig, std::uint32_t width_px,
                                        std::uint32_t height_px);
// Each eye's image size as the backend draws it: DisplayInfo's, else the
// protocol's resolution (a backend that does not say draws at the size it is asked for).
std::pair<std::uint32_t, std::uint32_t> eye_image_size(const io::DisplayInfo& info, std::uint32_t protocol_width_px,
                                                       std::uint32_t protocol_height_px);
// The rig a record describes; exact (every double is stored as it was).
renderer::StereoRig rig_from_record(const data::ViewGeometry& geometry);

}  // namespace curvlab::harness::runner
