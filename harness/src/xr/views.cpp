#include "curvlab/harness/xr/views.hpp"

#include <cmath>

namespace curvlab::harness::xr {

FrustumTangents tangents(const AsymmetricFov& fov) {
  return {std::tan(fov.left_rad), std::tan(fov.right_rad), std::tan(fov.down_rad),
          std::tan(fov.up_rad)};
}

}  // namespace curvlab::harness::xr
