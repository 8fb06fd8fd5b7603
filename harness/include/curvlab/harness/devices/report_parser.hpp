// Raw input reports → response press/release events. Pure: no I/O, no clock;
// the caller passes the report's timestamp.
#pragma once

#include "curvlab/harness/devices/mapping.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace curvlab::harness::devices {

struct ResponseEvent {
  enum class Edge { Down, Up };
  std::string response;
  Edge edge = Edge::Down;
  std::int64_t t_ns = 0;     // session clock when the report was read
  int binding_index = 0;     // which binding of the mapping fired
};

// Remembers which bindings are held so that each report yields only changes
// (a held button does not repeat). Not thread-safe; one per device.
class ReportParser {
 public:
  explicit ReportParser(DeviceMapping mapping);

  // Events caused by one report, in binding order. Reports with another
  // report ID are ignored; a report too short for a binding leaves that
  // binding's state unchanged and counts in short_reports().
  std::vector<ResponseEvent> parse(std::span<const std::uint8_t> report, std::int64_t t_ns);

  // Releases every held binding (e.g. when the device disappears), so that
  // no response stays pressed forever.
  std::vector<ResponseEvent> release_all(std::int64_t t_ns);

  [[nodiscard]] const DeviceMapping& mapping() const { return mapping_; }
  [[nodiscard]] std::uint64_t short_reports() const { return short_reports_; }

 private:
  DeviceMapping mapping_;
  std::vector<bool> held_;
  std::uint64_t short_reports_ = 0;
};

}  // namespace curvlab::harness::devices
