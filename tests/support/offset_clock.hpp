// A session clock that reads the machine's monotonic clock plus a fixed
// offset: a second station's clock on the same machine, for checking the
// link's clock estimate against a known true offset.
#pragma once

#include <cstdint>

#include <curvlab/harness/io/clock.hpp>

namespace curvlab::test {

class OffsetClock final : public harness::io::Clock {
 public:
  explicit OffsetClock(std::int64_t offset_ns) : offset_ns_(offset_ns) {}
  [[nodiscard]] std::int64_t now_ns() const override { return steady_.now_ns() + offset_ns_; }

 private:
  harness::io::SteadyClock steady_;
  std::int64_t offset_ns_;
};

}  // namespace curvlab::test
