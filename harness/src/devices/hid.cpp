#include "curvlab/harness/devices/hid.hpp"

#include <hidapi.h>

#include <cstdio>
#include <mutex>

namespace curvlab::harness::devices {
namespace {

std::mutex g_library_mutex;
int g_library_refs = 0;  // guarded by g_library_mutex

// hidapi hands out wchar_t strings (UTF-32 on Linux); curvlab speaks UTF-8.
std::string utf8(const wchar_t* text) {
  std::string out;
  if (text == nullptr) return out;
  for (; *text != 0; ++text) {
    auto c = static_cast<char32_t>(*text);
    if (c > 0x10FFFF || (c >= 0xD800 && c <= 0xDFFF)) c = 0xFFFD;
    if (c < 0x80) {
      out += static_cast<char>(c);
    } else if (c < 0x800) {
      out += static_cast<char>(0xC0 | (c >> 6));
      out += static_cast<char>(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
      out += static_cast<char>(0xE0 | (c >> 12));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (c & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (c >> 18));
      out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (c & 0x3F));
    }
  }
  return out;
}

std::string hex4(std::uint16_t v) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04x", static_cast<unsigned>(v));
  return buf;
}

harness::Error device_error(std::string message) {
  return {harness::Error::Kind::device, std::move(message)};
}

}  // namespace

harness::Result<HidLibrary> HidLibrary::open() {
  const std::lock_guard lock(g_library_mutex);
  if (g_library_refs == 0 && hid_init() != 0)
    return device_error("hidapi could not start: " + utf8(hid_error(nullptr)));
  ++g_library_refs;
  HidLibrary library;
  library.owns_ = true;
  return library;
}

HidLibrary::HidLibrary(HidLibrary&& other) noexcept : owns_(other.owns_) { other.owns_ = false; }

HidLibrary& HidLibrary::operator=(HidLibrary&& other) noexcept {
  if (this != &other) {
    HidLibrary old(std::move(*this));
    owns_ = other.owns_;
    other.owns_ = false;
  }
  return *this;
}

HidLibrary::~HidLibrary() {
  if (!owns_) return;
  const std::lock_guard lock(g_library_mutex);
  if (--g_library_refs == 0) hid_exit();
}

std::vector<HidDeviceInfo> HidLibrary::enumerate() const {
  std::vector<HidDeviceInfo> out;
  // hid_enumerate returns NULL both for "none" and for failure; either way
  // there is nothing to open, and `curvlab devices` says so.
  hid_device_info* list = hid_enumerate(0, 0);
  for (const hid_device_info* d = list; d != nullptr; d = d->next) {
    HidDeviceInfo info;
    info.vendor_id = d->vendor_id;
    info.product_id = d->product_id;
    info.manufacturer = utf8(d->manufacturer_string);
    info.product = utf8(d->product_string);
    info.serial = utf8(d->serial_number);
    info.usage_page = d->usage_page;
    info.usage = d->usage;
    info.interface_number = d->interface_number;
    info.release = d->release_number;
    info.path = d->path != nullptr ? d->path : "";
    out.push_back(std::move(info));
  }
  hid_free_enumeration(list);
  return out;
}

void HidDevice::Closer::operator()(hid_device_* device) const noexcept { hid_close(device); }

harness::Result<HidDevice> HidDevice::open(const HidDeviceInfo& info) {
  auto library = HidLibrary::open();
  if (!library) return library.error();
  hid_device* device = hid_open_path(info.path.c_str());
  if (device == nullptr)
    return device_error("cannot open " + describe(info) + " at " + info.path + ": " +
                        utf8(hid_error(nullptr)) +
                        " (is the user allowed to read it? see docs/devices.md, udev rule)");
  return HidDevice(std::move(library).value(), device, describe(info));
}

harness::Result<std::size_t> HidDevice::read(std::span<std::uint8_t> buffer, int timeout_ms) {
  const int n = hid_read_timeout(device_.get(), buffer.data(), buffer.size(), timeout_ms);
  if (n < 0) return device_error(label_ + " stopped responding: " + utf8(hid_error(device_.get())));
  return static_cast<std::size_t>(n);
}

std::string describe(const HidDeviceInfo& info) {
  std::string out = hex4(info.vendor_id) + ":" + hex4(info.product_id);
  std::string name = info.manufacturer;
  if (!info.product.empty()) name += (name.empty() ? "" : " ") + info.product;
  if (!name.empty()) out += " " + name;
  out += " (usage 0x" + hex4(info.usage_page) + ":0x" + hex4(info.usage) + ")";
  return out;
}

}  // namespace curvlab::harness::devices
