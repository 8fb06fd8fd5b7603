// The partner's clock on this station's session clock (docs/shared_play.md,
// "Clocks"): NTP-style exchanges (RFC 5905, on-wire protocol) — t1 this
// station sends a ping, t2 the partner receives it, t3 the partner answers,
// t4 the answer arrives; t1 and t4 on this clock, t2 and t3 on the partner's.
//
//   offset θ = ((t2 − t1) + (t3 − t4)) / 2   (partner clock − this clock)
//   round trip δ = (t4 − t1) − (t3 − t2)
//
// θ is exact when the two directions take equally long; otherwise it is off
// by half the difference, which is at most δ/2 (the stated uncertainty). Of
// the last `window` exchanges the one with the shortest round trip is used
// (NTP's clock filter: a short round trip had the least queueing, so the
// least room for asymmetry). With pings every 250 ms and a window of 32 the
// estimate follows eight seconds of history: two crystal clocks 50 ppm apart
// drift 0.4 ms in that time, so the estimate is recomputed continuously, not
// fixed at the handshake.
//
// Pure, not thread-safe: one estimator per link, used by the link's thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>

#include <curvlab/harness/net/messages.hpp>

namespace curvlab::harness::net {

struct ClockSample {
  std::int64_t t1_ns = 0, t2_ns = 0, t3_ns = 0, t4_ns = 0;
  [[nodiscard]] std::int64_t offset_ns() const;
  [[nodiscard]] std::int64_t round_trip_ns() const;
};

struct ClockEstimate {
  bool valid = false;
  std::int64_t offset_ns = 0;       // partner's clock minus this station's
  std::int64_t round_trip_ns = 0;   // of the exchange the offset comes from
  std::int64_t uncertainty_ns = 0;  // half that round trip: the most asymmetry can shift θ
  std::int64_t at_ns = 0;           // this station's clock, when that exchange completed
  std::size_t samples = 0;          // exchanges in the window
};

class ClockEstimator {
 public:
  explicit ClockEstimator(std::size_t window = 32);
  // False (and nothing kept) for an exchange that cannot be real: an answer
  // before its ping, or the partner answering before it received.
  bool add(const ClockSample& s);
  bool add(const Pong& pong, std::int64_t t4_ns) { return add({pong.t1_ns, pong.t2_ns, pong.t3_ns, t4_ns}); }
  [[nodiscard]] ClockEstimate estimate() const;
  // A time on the partner's clock as this station's clock reads it.
  [[nodiscard]] std::int64_t to_local_ns(std::int64_t partner_ns) const;

 private:
  std::size_t window_;
  std::deque<ClockSample> samples_;
};

}  // namespace curvlab::harness::net
