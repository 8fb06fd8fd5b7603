// `curvlab devices` (HID response devices and mapping files) and
// `curvlab xr-check` (can this machine run the xr backend?).
#include "common.hpp"
#include "lsl_args.hpp"

#include "curvlab/harness/devices/hid.hpp"
#include "curvlab/harness/devices/mapping.hpp"
#include "curvlab/harness/xr/instance.hpp"

#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>

namespace curvlab::harness::cli {
namespace {

struct DevicesArgs {
  bool json = false;
  bool show_serial = false;
  std::string mapping;
};

void run_devices(const DevicesArgs& a) {
  using namespace curvlab::harness::devices;
  std::optional<MappingFile> mapping;
  if (!a.mapping.empty()) {
    auto loaded = load_mapping(a.mapping);
    if (!loaded) raise(loaded.error());
    mapping = std::move(loaded).value();
  }
  auto opened = HidLibrary::open();
  if (!opened) raise(opened.error());
  const auto found = opened.value().enumerate();

  Json doc;
  Json list = Json::array();
  for (const auto& d : found) {
    Json item;
    item["vendor_id"] = d.vendor_id;
    item["product_id"] = d.product_id;
    item["manufacturer"] = d.manufacturer;
    item["product"] = d.product;
    if (a.show_serial) item["serial"] = d.serial;
    item["usage_page"] = d.usage_page;
    item["usage"] = d.usage;
    item["interface"] = d.interface_number;
    item["path"] = d.path;
    if (mapping) {
      const DeviceMapping* m = mapping->find(d);
      item["mapping"] = m != nullptr ? Json(m->name) : Json(nullptr);
    }
    list.push_back(std::move(item));
  }
  if (a.json) {
    doc["devices"] = list;
    doc["lsl"] = lsl_build_line();
    if (mapping) {
      Json names = Json::array();
      for (const auto& m : mapping->devices) names.push_back(m.name);
      doc["mapping_file"] = mapping->file;
      doc["mapping_devices"] = names;
    }
    print_result(doc, true);
    return;
  }
  std::cout << "curvlab " << lsl_build_line() << '\n';
  if (mapping)
    std::cout << "mapping file " << mapping->file << ": " << mapping->devices.size()
              << " device mapping(s), valid\n";
  if (found.empty()) {
    std::cout << "no HID devices found (none connected, or no permission to read "
                 "/dev/hidraw*; see docs/devices.md)\n";
    return;
  }
  for (const auto& d : found) {
    std::cout << describe(d) << "  " << d.path;
    if (a.show_serial && !d.serial.empty()) std::cout << "  serial " << d.serial;
    if (mapping) {
      const DeviceMapping* m = mapping->find(d);
      std::cout << "  → " << (m != nullptr ? "mapping \"" + m->name + "\"" : "no mapping");
    }
    std::cout << '\n';
  }
}

void run_xr_check(bool as_json) {
  auto result = curvlab::harness::xr::probe("curvlab xr-check");
  if (!result) {
    const auto& e = result.error();
    if (as_json) {
      Json doc;
      doc["ok"] = false;
      if (const auto f = curvlab::harness::xr::failed_call(e)) {
        doc["call"] = f->call;
        doc["result"] = curvlab::harness::xr::result_name(f->result);
        doc["result_code"] = static_cast<int>(f->result);
      }
      doc["message"] = e.message;
      doc["lsl"] = lsl_build_line();
      print_result(doc, true);
    }
    throw RuntimeFailure("xr backend unavailable: " + e.message);
  }
  const auto& r = result.value();
  Json doc;
  doc["ok"] = true;
  doc["runtime"] = r.runtime_name + " " + r.runtime_version;
  doc["system"] = r.system_name;
  doc["orientation_tracking"] = r.orientation_tracking;
  doc["position_tracking"] = r.position_tracking;
  doc["max_swapchain"] = std::to_string(r.max_swapchain_width) + "x" +
                         std::to_string(r.max_swapchain_height);
  doc["api_layers"] = r.api_layers;
  doc["extensions"] = r.extensions;
  doc["lsl"] = lsl_build_line();
  print_result(doc, as_json);
}

}  // namespace

void add_devices_commands(CLI::App& app) {
  {
    auto args = std::make_shared<DevicesArgs>();
    auto* cmd = app.add_subcommand("devices", "list HID response devices (button boxes, pedals, "
                                              "gamepads) and check a mapping file");
    cmd->add_flag("--json", args->json, "print JSON");
    cmd->add_flag("--show-serial", args->show_serial,
                  "include serial numbers (they identify one unit; off by default)");
    cmd->add_option("--mapping", args->mapping,
                    "a response mapping file (TOML) to validate and match against the devices");
    cmd->callback([args] { run_devices(*args); });
  }
  {
    auto as_json = std::make_shared<bool>(false);
    auto* cmd = app.add_subcommand(
        "xr-check", "check that an OpenXR runtime with Vulkan support and a headset are present");
    cmd->add_flag("--json", *as_json, "print JSON");
    cmd->callback([as_json] { run_xr_check(*as_json); });
  }
}

}  // namespace curvlab::harness::cli
