// Report parsing with recorded input reports of two kinds of device:
// a boot-protocol keyboard (8 bytes: modifiers, reserved, six key codes) and
// a USB gamepad (report ID 1, 12 buttons in two bytes, four 8-bit axes).
#include "curvlab/harness/devices/mapping.hpp"
#include "curvlab/harness/devices/report_parser.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace {

using namespace curvlab::harness::devices;

MappingFile parse_ok(const std::string& text) {
  auto r = parse_mapping(text, "test.toml");
  if (!r) {
    ADD_FAILURE() << r.error().message;
    return {};
  }
  return std::move(r).value();
}

std::string summary(const std::vector<ResponseEvent>& events) {
  std::string out;
  for (const auto& e : events)
    out += (out.empty() ? "" : " ") + e.response + (e.edge == ResponseEvent::Edge::Down ? "+" : "-");
  return out;
}

constexpr const char* kKeyboardMapping = R"(
[[device]]
name = "keyboard"
usage_page = 0x01
usage = 0x06

[[device.binding]]
response = "convex"
kind = "key"
keycode = 0x04   # a

[[device.binding]]
response = "concave"
kind = "key"
keycode = 0x07   # d

[[device.binding]]
response = "straight"
kind = "key"
keycode = 0x2C   # space

[[device.binding]]
response = "confirm"
kind = "bit"
byte = 0
bit = 1          # left shift
)";

TEST(ReportParser, BootKeyboard) {
  const auto file = parse_ok(kKeyboardMapping);
  ASSERT_EQ(file.devices.size(), 1u);
  ReportParser parser(file.devices[0]);
  // Recorded reports: press a; press space while a is held (a moves to the
  // first slot, space to the second); release a (space shifts to slot one);
  // left shift + space; all released.
  const std::vector<std::vector<std::uint8_t>> reports = {
      {0x00, 0x00, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00},
      {0x00, 0x00, 0x04, 0x2C, 0x00, 0x00, 0x00, 0x00},
      {0x00, 0x00, 0x2C, 0x00, 0x00, 0x00, 0x00, 0x00},
      {0x02, 0x00, 0x2C, 0x00, 0x00, 0x00, 0x00, 0x00},
      {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00},
  };
  std::vector<std::string> seen;
  for (std::size_t i = 0; i < reports.size(); ++i)
    seen.push_back(summary(parser.parse(reports[i], static_cast<std::int64_t>(i) * 1000)));
  EXPECT_EQ(seen, (std::vector<std::string>{"convex+", "straight+", "convex-", "confirm+",
                                            "straight- confirm-"}));
}

TEST(ReportParser, KeyboardRolloverErrorReportPressesNothing) {
  ReportParser parser(parse_ok(kKeyboardMapping).devices[0]);
  // Phantom state: every key slot reads ErrorRollOver (0x01).
  const std::vector<std::uint8_t> rollover = {0x00, 0x00, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01};
  EXPECT_TRUE(parser.parse(rollover, 0).empty());
}

TEST(ReportParser, TimestampsAndBindingIndexCarryThrough) {
  ReportParser parser(parse_ok(kKeyboardMapping).devices[0]);
  const std::vector<std::uint8_t> d = {0x00, 0x00, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00};
  const auto events = parser.parse(d, 123456789);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].t_ns, 123456789);
  EXPECT_EQ(events[0].binding_index, 1);
  // Held: the same report again changes nothing.
  EXPECT_TRUE(parser.parse(d, 2).empty());
}

constexpr const char* kGamepadMapping = R"(
[[device]]
name = "gamepad"
vendor_id = 0x046d
product_id = 0xc216
report_id = 1

[[device.binding]]
response = "left"
kind = "bit"
byte = 0
bit = 4          # button 5 (left shoulder)

[[device.binding]]
response = "right"
kind = "bit"
byte = 0
bit = 5          # button 6 (right shoulder)

[[device.binding]]
response = "start"
kind = "bit"
byte = 1
bit = 1          # button 10

[[device.binding]]
response = "more"
kind = "axis"
byte = 3         # left stick Y, 0 up … 255 down, 128 centre
below = 40
release = 90

[[device.binding]]
response = "trigger"
kind = "axis"
byte = 4
bits = 16
signed = true
above = 16000
)";

TEST(ReportParser, GamepadButtonsAndAxesWithHysteresis) {
  const auto file = parse_ok(kGamepadMapping);
  ReportParser parser(file.devices[0]);
  // Layout after the report ID: buttons 1–8, buttons 9–12, stick X, stick Y,
  // then a signed 16-bit little-endian trigger axis.
  auto report = [](std::uint8_t b0, std::uint8_t b1, std::uint8_t x, std::uint8_t y,
                   std::int16_t trig) {
    const auto t = static_cast<std::uint16_t>(trig);
    return std::vector<std::uint8_t>{0x01, b0, b1, x, y, static_cast<std::uint8_t>(t & 0xFF),
                                     static_cast<std::uint8_t>(t >> 8)};
  };
  std::vector<std::string> seen;
  seen.push_back(summary(parser.parse(report(0x10, 0x00, 128, 128, 0), 1)));      // left
  seen.push_back(summary(parser.parse(report(0x30, 0x02, 128, 128, 0), 2)));      // +right, start
  seen.push_back(summary(parser.parse(report(0x00, 0x00, 128, 30, 0), 3)));       // stick up
  seen.push_back(summary(parser.parse(report(0x00, 0x00, 128, 60, 0), 4)));       // inside hysteresis
  seen.push_back(summary(parser.parse(report(0x00, 0x00, 128, 95, 0), 5)));       // released
  seen.push_back(summary(parser.parse(report(0x00, 0x00, 128, 128, 20000), 6)));  // trigger
  seen.push_back(summary(parser.parse(report(0x00, 0x00, 128, 128, -20000), 7))); // negative: up
  EXPECT_EQ(seen, (std::vector<std::string>{"left+", "right+ start+", "left- right- start- more+",
                                            "", "more-", "trigger+", "trigger-"}));
}

TEST(ReportParser, OtherReportIdsAndShortReportsAreIgnored) {
  ReportParser parser(parse_ok(kGamepadMapping).devices[0]);
  const std::vector<std::uint8_t> other_id = {0x02, 0xFF, 0xFF, 0, 0, 0xFF, 0x7F};
  EXPECT_TRUE(parser.parse(other_id, 1).empty());
  const std::vector<std::uint8_t> short_report = {0x01, 0x10};
  // Bit bindings within the two bytes still work; the axes cannot be read.
  EXPECT_EQ(summary(parser.parse(short_report, 2)), "left+");
  EXPECT_EQ(parser.short_reports(), 1u);
  EXPECT_EQ(summary(parser.release_all(3)), "left-");
}

}  // namespace
