// The session's one monotonic clock (DESIGN.md §6): nanoseconds since an
// arbitrary epoch, never adjusted. Everything that timestamps an event —
// response devices, frames, tracking samples — reads the same Clock so that
// the times can be subtracted. The session runner owns the clock and hands a
// reference to each producer.
#pragma once

#include <chrono>
#include <cstdint>

namespace curvlab::harness::io {

// Thread-safety: now_ns() may be called from any thread concurrently.
class Clock {
 public:
  virtual ~Clock() = default;
  [[nodiscard]] virtual std::int64_t now_ns() const = 0;
};

// std::chrono::steady_clock (CLOCK_MONOTONIC on Linux).
class SteadyClock final : public Clock {
 public:
  [[nodiscard]] std::int64_t now_ns() const override {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }
};

}  // namespace curvlab::harness::io
