// HID response devices (button boxes, pedals, gamepads, keyboards) through
// hidapi's hidraw backend: library lifetime, enumeration, and one open device.
#pragma once

#include "curvlab/harness/result.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

struct hid_device_;

namespace curvlab::harness::devices {

struct HidDeviceInfo {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string manufacturer;
  std::string product;
  // The serial number identifies one physical unit; it is kept out of logs
  // and listings unless asked for (DESIGN.md §7: no identifying data by default).
  std::string serial;
  std::uint16_t usage_page = 0;
  std::uint16_t usage = 0;
  int interface_number = -1;
  std::uint16_t release = 0;
  std::string path;  // hidraw node, e.g. /dev/hidraw3; what HidDevice::open takes
};

// One reference to the hidapi library (hid_init on first, hid_exit on last).
// hidapi's state is process-wide, so references are counted under a mutex;
// any number of HidLibrary objects may exist on any threads. Move-only.
class HidLibrary {
 public:
  // An expected failure (no permission, device gone…) is an Error of kind
  // `device`, with a message a person can act on.
  static harness::Result<HidLibrary> open();
  HidLibrary(HidLibrary&& other) noexcept;
  HidLibrary& operator=(HidLibrary&& other) noexcept;
  HidLibrary(const HidLibrary&) = delete;
  HidLibrary& operator=(const HidLibrary&) = delete;
  ~HidLibrary();

  // Every HID interface the hidraw backend can see. No devices (or no
  // /dev/hidraw* at all) is an empty list, not an error.
  [[nodiscard]] std::vector<HidDeviceInfo> enumerate() const;

 private:
  HidLibrary() = default;
  bool owns_ = false;
};

// Where reports come from: an open HID device, or (in tests and replays) a
// recorded sequence. read() blocks at most timeout_ms and returns the report
// length, 0 on timeout, or an Error (kind `device`) when the device is gone.
class ReportSource {
 public:
  virtual ~ReportSource() = default;
  virtual harness::Result<std::size_t> read(std::span<std::uint8_t> buffer, int timeout_ms) = 0;
  [[nodiscard]] virtual std::string label() const = 0;
};

// One open hid_device. Move-only owner; closed by the destructor. It holds
// its own HidLibrary reference, so hidapi stays initialised while it is open.
// Not thread-safe: one thread reads it (DeviceReader's).
class HidDevice final : public ReportSource {
 public:
  static harness::Result<HidDevice> open(const HidDeviceInfo& info);
  harness::Result<std::size_t> read(std::span<std::uint8_t> buffer, int timeout_ms) override;
  [[nodiscard]] std::string label() const override { return label_; }

 private:
  struct Closer {
    void operator()(hid_device_* device) const noexcept;
  };
  HidDevice(HidLibrary library, hid_device_* device, std::string label)
      : library_(std::move(library)), device_(device), label_(std::move(label)) {}
  HidLibrary library_;  // declared first: outlives device_
  std::unique_ptr<hid_device_, Closer> device_;
  std::string label_;
};

// "046d:c216 Logitech Dual Action (usage 0x01:0x05)" — no serial.
std::string describe(const HidDeviceInfo& info);

}  // namespace curvlab::harness::devices
