#include <curvlab/harness/net/partner_poses.hpp>

#include <algorithm>

namespace curvlab::harness::net {

PartnerPoseBuffer::PartnerPoseBuffer(std::int64_t max_extrapolation_ns, std::int64_t hold_ns, std::size_t capacity)
    : max_extrapolation_ns_(max_extrapolation_ns), hold_ns_(hold_ns), capacity_(std::max<std::size_t>(capacity, 2)) {}

void PartnerPoseBuffer::push(const PoseFrame& frame, std::int64_t local_ns) {
  if (!samples_.empty() && (frame.sequence <= samples_.back().frame.sequence || local_ns <= samples_.back().t_ns))
    return;
  samples_.push_back({local_ns, frame});
  while (samples_.size() > capacity_) samples_.pop_front();
}

PartnerPose PartnerPoseBuffer::at(std::int64_t local_ns) const {
  PartnerPose out;
  if (samples_.empty()) return out;
  const Sample& newest = samples_.back();
  if (local_ns - newest.t_ns > hold_ns_) return out;

  // The pair around local_ns, or the newest two (extrapolation), or one sample.
  const Sample* a = &samples_.front();
  const Sample* b = &samples_.front();
  if (local_ns >= newest.t_ns) {
    b = &newest;
    a = samples_.size() >= 2 ? &samples_[samples_.size() - 2] : &newest;
  } else if (local_ns <= samples_.front().t_ns) {
    a = b = &samples_.front();
  } else {
    const auto it = std::upper_bound(samples_.begin(), samples_.end(), local_ns,
                                     [](std::int64_t t, const Sample& s) { return t < s.t_ns; });
    b = &*it;
    a = &*(it - 1);
  }
  const std::int64_t t = std::min(local_ns, newest.t_ns + max_extrapolation_ns_);
  double u = 1.0;
  if (b->t_ns != a->t_ns) u = static_cast<double>(t - a->t_ns) / static_cast<double>(b->t_ns - a->t_ns);
  u = std::max(u, 0.0);

  const geometry::Space space{b->frame.space, b->frame.radius_m};
  out.valid = true;
  out.tracked = static_cast<std::uint8_t>(a->frame.tracked & b->frame.tracked);
  out.newest_sample_ns = b->t_ns;
  out.newest_sequence = b->frame.sequence;
  out.extrapolated = local_ns > newest.t_ns;
  for (int d = 0; d < PoseFrame::kDevices; ++d) {
    if (!(out.tracked & (1u << d))) {
      out.pose[d] = b->frame.pose[d];
      continue;
    }
    geometry::Isometry blend{a->frame.pose[d].m * (1.0 - u) + b->frame.pose[d].m * u};
    out.pose[d] = geometry::reorthonormalize(space, blend);
  }
  return out;
}

}  // namespace curvlab::harness::net
