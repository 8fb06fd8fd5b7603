#include "curvlab/harness/runner/view_record.hpp"

namespace curvlab::harness::runner {

data::ViewGeometry record_view_geometry(const renderer::StereoRig& rig, std::uint32_t width_px,
                                        std::uint32_t height_px) {
  data::ViewGeometry g;
  g.width_px = width_px;
  g.height_px = height_px;
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& e = rig.eyes[i];
    auto& out = g.eyes[i];
    out.position_m = {e.position_m.x, e.position_m.y, e.position_m.z};
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) out.rotation[static_cast<std::size_t>(c * 3 + r)] = e.rotation[c][r];
    out.fov_rad = {e.fov.angle_left_rad, e.fov.angle_right_rad, e.fov.angle_up_rad, e.fov.angle_down_rad};
  }
  return g;
}

std::pair<std::uint32_t, std::uint32_t> eye_image_size(const io::DisplayInfo& info, std::uint32_t protocol_width_px,
                                                       std::uint32_t protocol_height_px) {
  if (info.eye_width_px > 0 && info.eye_height_px > 0) return {info.eye_width_px, info.eye_height_px};
  return {protocol_width_px, protocol_height_px};
}

renderer::StereoRig rig_from_record(const data::ViewGeometry& g) {
  renderer::StereoRig rig;
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& e = g.eyes[i];
    auto& out = rig.eyes[i];
    out.position_m = {e.position_m[0], e.position_m[1], e.position_m[2]};
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) out.rotation[c][r] = e.rotation[static_cast<std::size_t>(c * 3 + r)];
    out.fov = {e.fov_rad[0], e.fov_rad[1], e.fov_rad[2], e.fov_rad[3]};
  }
  return rig;
}

}  // namespace curvlab::harness::runner
