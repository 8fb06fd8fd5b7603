#include "curvlab/harness/devices/report_parser.hpp"

#include <optional>

namespace curvlab::harness::devices {
namespace {

// nullopt when the report is too short for the binding.
std::optional<bool> is_pressed(const Binding& binding, std::span<const std::uint8_t> data,
                               bool was_held) {
  const auto size = static_cast<int>(data.size());
  if (const auto* bit = std::get_if<BitBinding>(&binding.input)) {
    if (bit->byte >= size) return std::nullopt;
    return ((data[static_cast<std::size_t>(bit->byte)] >> bit->bit) & 1U) != 0;
  }
  if (const auto* key = std::get_if<KeyBinding>(&binding.input)) {
    if (key->last_byte >= size) return std::nullopt;
    for (int i = key->first_byte; i <= key->last_byte; ++i)
      if (data[static_cast<std::size_t>(i)] == key->keycode) return true;
    return false;
  }
  const auto& axis = std::get<AxisBinding>(binding.input);
  const int width = axis.bits / 8;
  if (axis.byte + width > size) return std::nullopt;
  const auto lo = static_cast<unsigned>(data[static_cast<std::size_t>(axis.byte)]);
  const unsigned raw =
      width == 2 ? lo | (static_cast<unsigned>(data[static_cast<std::size_t>(axis.byte + 1)]) << 8)
                 : lo;
  int value = static_cast<int>(raw);
  if (axis.is_signed && raw >= (1U << (axis.bits - 1))) value -= 1 << axis.bits;
  // Hysteresis: a held axis is released only past release_at.
  if (axis.direction == AxisBinding::Direction::Above)
    return was_held ? value >= axis.release_at : value >= axis.press_at;
  return was_held ? value <= axis.release_at : value <= axis.press_at;
}

}  // namespace

ReportParser::ReportParser(DeviceMapping mapping)
    : mapping_(std::move(mapping)), held_(mapping_.bindings.size(), false) {}

std::vector<ResponseEvent> ReportParser::parse(std::span<const std::uint8_t> report,
                                               std::int64_t t_ns) {
  std::vector<ResponseEvent> events;
  if (mapping_.report_id) {
    if (report.empty() || report[0] != *mapping_.report_id) return events;
    report = report.subspan(1);
  }
  bool short_report = false;
  for (std::size_t i = 0; i < mapping_.bindings.size(); ++i) {
    const auto pressed = is_pressed(mapping_.bindings[i], report, held_[i]);
    if (!pressed) {
      short_report = true;
      continue;
    }
    if (*pressed == held_[i]) continue;
    held_[i] = *pressed;
    events.push_back({mapping_.bindings[i].response,
                      *pressed ? ResponseEvent::Edge::Down : ResponseEvent::Edge::Up, t_ns,
                      static_cast<int>(i)});
  }
  if (short_report) ++short_reports_;
  return events;
}

std::vector<ResponseEvent> ReportParser::release_all(std::int64_t t_ns) {
  std::vector<ResponseEvent> events;
  for (std::size_t i = 0; i < held_.size(); ++i) {
    if (!held_[i]) continue;
    held_[i] = false;
    events.push_back({mapping_.bindings[i].response, ResponseEvent::Edge::Up, t_ns,
                      static_cast<int>(i)});
  }
  return events;
}

}  // namespace curvlab::harness::devices
