// The partner's head, hands and cue at this station's display time
// (docs/shared_play.md, "The partner seen"). Pose frames arrive stamped with
// the partner's display time; the link's clock estimate puts that on this
// station's clock. A frame drawn at local time t interpolates between the two
// samples around t, or, when t is past the newest sample (the usual case:
// the newest sample is at least the network's one-way delay old), extrapolates
// from the newest two — at most max_extrapolation_ns past the newest, after
// which the pose is held there, and after hold_ns with nothing new it is no
// longer valid (the partner is drawn as lost).
//
// Isometries are blended entry-wise and re-orthonormalised on the space
// (geometry::reorthonormalize): for samples a frame apart the blend is the
// geodesic interpolation to second order in the step.
//
// Pure; not thread-safe (one per frame loop).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>

#include <curvlab/harness/net/messages.hpp>

namespace curvlab::harness::net {

struct PartnerPose {
  bool valid = false;
  std::uint8_t tracked = 0;        // bit d: device d is tracked in the samples used
  std::array<geometry::Isometry, PoseFrame::kDevices> pose{};
  std::int64_t newest_sample_ns = 0;  // local time of the newest sample used
  std::uint32_t newest_sequence = 0;
  bool extrapolated = false;
};

class PartnerPoseBuffer {
 public:
  explicit PartnerPoseBuffer(std::int64_t max_extrapolation_ns = 50'000'000, std::int64_t hold_ns = 500'000'000,
                             std::size_t capacity = 64);
  // A frame whose display time on this station's clock is local_ns. Frames
  // must come in sequence order (the link drops late ones); a frame not
  // later than the newest is ignored.
  void push(const PoseFrame& frame, std::int64_t local_ns);
  [[nodiscard]] PartnerPose at(std::int64_t local_ns) const;
  [[nodiscard]] std::size_t size() const { return samples_.size(); }
  void clear() { samples_.clear(); }

 private:
  struct Sample {
    std::int64_t t_ns;
    PoseFrame frame;
  };
  std::int64_t max_extrapolation_ns_, hold_ns_;
  std::size_t capacity_;
  std::deque<Sample> samples_;
};

}  // namespace curvlab::harness::net
