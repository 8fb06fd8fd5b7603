// The response mapping file: which bits, keys or axis thresholds of which HID
// device mean which named response. Format: docs/devices.md.
#pragma once

#include "curvlab/harness/devices/hid.hpp"
#include "curvlab/harness/result.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace curvlab::harness::devices {

// A button that is one bit of one byte (gamepads, button boxes, keyboard
// modifiers).
struct BitBinding {
  int byte = 0;
  int bit = 0;
};

// A key of a boot-protocol keyboard: pressed while its usage code appears in
// any byte of [first_byte, last_byte] (the 6-key array, bytes 2–7).
struct KeyBinding {
  std::uint8_t keycode = 0;
  int first_byte = 2;
  int last_byte = 7;
};

// An axis (pedal, trigger, stick) read as an 8- or 16-bit little-endian
// integer; pressed when it crosses press_at in `direction`, released when it
// goes back past release_at (hysteresis, so a noisy pedal does not chatter).
struct AxisBinding {
  enum class Direction { Above, Below };
  int byte = 0;
  int bits = 8;
  bool is_signed = false;
  Direction direction = Direction::Above;
  int press_at = 0;
  int release_at = 0;
};

struct Binding {
  std::string response;  // the name the protocol's judgements use
  std::variant<BitBinding, KeyBinding, AxisBinding> input;
};

// How a device is recognised: vendor/product and/or usage page/usage; unset
// fields match anything (at least one is set).
struct DeviceMatch {
  std::optional<std::uint16_t> vendor_id, product_id, usage_page, usage;
  [[nodiscard]] bool matches(const HidDeviceInfo& info) const;
};

struct DeviceMapping {
  std::string name;
  DeviceMatch match;
  // Devices with numbered reports send the report ID as byte 0; when set,
  // only reports with this ID are parsed and byte offsets count after it.
  std::optional<std::uint8_t> report_id;
  std::vector<Binding> bindings;
};

struct MappingFile {
  std::string file;
  std::vector<DeviceMapping> devices;
  // The first device mapping that matches a connected device, if any.
  [[nodiscard]] const DeviceMapping* find(const HidDeviceInfo& info) const;
};

// A bad file is an Error (kind bad_input; not_found when it cannot be read)
// whose message is "file:line:column: field: message": where, which field,
// what was expected.
harness::Result<MappingFile> parse_mapping(std::string_view text, const std::string& file_name);
harness::Result<MappingFile> load_mapping(const std::filesystem::path& path);

}  // namespace curvlab::harness::devices
